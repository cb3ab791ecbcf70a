#include "stirred_tank.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

class StirredTank : public UnitBase<StirredTank> {
 public:
  std::string type() const override { return "stirred_tank"; }
  void declare(UnitSpec& s, Settings&) override {
    p_mass_ = s.add_param({"mass", "kg", 100.0, 1e-6, 1e9, "liquid hold-up", "operating input"});
    p_cp_ = s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5,
                         "heat capacity of the liquid", "water, paper 001, Table 6"});
    p_q_ = s.add_param({"Q", "W", 0.0, -1e9, 1e9, "heating duty", "operating input"});
    p_t0_ = s.add_param({"T0", "K", 293.15, 200.0, 700.0, "initial temperature", "initial state (user)"});
    p_w0_ = s.add_param({"w0", "kg/kg", 0.0, 0.0, 1.0, "initial solute mass fraction", "initial state (user)"});
    sT_ = s.add_state("T", StateKind::Differential, "K", 300.0);
    sW_ = s.add_state("w", StateKind::Differential, "kg/kg", 1.0);
    in_ = s.add_port("in", streams::liquid(), PortDir::In);
    const PortId out = s.add_port("out", streams::liquid(), PortDir::Out);
    s.forward(out, liquid::kMdot, in_, liquid::kMdot);  // constant hold-up: out = in
    s.provide(out, liquid::kT, sT_);
    s.provide(out, liquid::kW, sW_);
    o_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
    o_solids_ = s.add_output("balance_solids_hold", "kg", OutputRole::kBalanceHold, "solids");
    o_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
    q_heat_ = s.add_quadrature("balance_energy_in", "J", 1e8, OutputRole::kBalanceIn, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_in = c.port(in_, liquid::kMdot);
    const T& mass = c.par(p_mass_);
    const T& cp = c.par(p_cp_);
    // M cp dT/dt = m_in cp (T_in - T) + Q, divided by M cp for scaling
    c.res(sT_) = c.xd(sT_) - (m_in * (c.port(in_, liquid::kT) - c.x(sT_)) + c.par(p_q_) / cp) / mass;
    c.res(sW_) = c.xd(sW_) - m_in * (c.port(in_, liquid::kW) - c.x(sW_)) / mass;
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_heat_.i] = c.par(p_q_);
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sT_) = c.par(p_t0_);
    c.x(sW_) = c.par(p_w0_);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_water_) = c.par(p_mass_);
    c.out(o_solids_) = c.par(p_mass_) * c.x(sW_);
    c.out(o_energy_) = c.par(p_mass_) * props::liquid_water_enthalpy(c.x(sT_), c.par(p_cp_));
  }

 private:
  ParamId p_mass_, p_cp_, p_q_, p_t0_, p_w0_;
  StateId sT_, sW_;
  PortId in_;
  OutputId o_water_, o_solids_, o_energy_;
  QuadId q_heat_;
};

}  // namespace

void register_stirred_tank(Registry<Unit>& r) {
  r.add("stirred_tank", "heated ideally mixed tank with constant hold-up",
        [] { return std::make_unique<StirredTank>(); });
}

}  // namespace granuflow::units
