// A stirred liquid tank at constant hold-up heated or cooled through a jacket at a given temperature. The jacket's
// duty is Newton's law of cooling with an overall coefficient U over the area A (e.g. Incropera et al., Fundamentals of
// Heat and Mass Transfer, 6th ed., Eq. (1.3a), and Eq. (11.1) for the overall coefficient):
//     M cp dT/dt = mdot_in cp (T_in - T) + U A (T_jacket - T)
//     M dw/dt    = mdot_in (w_in - w)
// Its ports carry granuflow's liquid stream (mass flow, temperature, solute fraction) like the built-in
// stirred_tank, and it reports the hold-ups and the jacket's heat as balance terms, so granuflow's balance check
// covers it.
#include <granuflow/properties.hpp>
#include <granuflow/unit.hpp>
#include <units/registry.hpp>

namespace {

using namespace granuflow;

class JacketedTank : public UnitBase<JacketedTank> {
 public:
  std::string type() const override { return "jacketed_tank"; }
  void declare(UnitSpec& s, Settings&) override {
    p_mass_ = s.add_param({"mass", "kg", 100.0, 1e-6, 1e9, "liquid hold-up", "operating input"});
    p_cp_ = s.add_param({"cp", "J/(kg K)", props::kCpWater, 1.0, 1e5, "heat capacity of the liquid",
                         "water, granuflow's constant (paper 001, Table 6)"});
    p_u_ = s.add_param(
        {"U", "W/(m2 K)", 0.0, 0.0, 1e5, "overall heat transfer coefficient of the jacket wall", "operating input"});
    p_a_ = s.add_param({"A", "m2", 1.0, 0.0, 1e4, "heat transfer area of the jacket", "operating input"});
    p_tj_ = s.add_param({"T_jacket", "K", 293.15, 200.0, 700.0, "jacket temperature", "operating input"});
    p_t0_ = s.add_param({"T0", "K", 293.15, 200.0, 700.0, "initial temperature", "initial state (user)"});
    p_w0_ = s.add_param({"w0", "kg/kg", 0.0, 0.0, 1.0, "initial solute mass fraction", "initial state (user)"});
    sT_ = s.add_state("T", StateKind::Differential, "K", 300.0);
    sW_ = s.add_state("w", StateKind::Differential, "kg/kg", 1.0);
    in_ = s.add_port("in", streams::liquid(), PortDir::In);
    const PortId out = s.add_port("out", streams::liquid(), PortDir::Out);
    s.forward(out, liquid::kMdot, in_, liquid::kMdot);  // constant hold-up: what enters leaves
    s.provide(out, liquid::kT, sT_);
    s.provide(out, liquid::kW, sW_);
    o_duty_ = s.add_output("Q_jacket", "W");
    o_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
    o_solids_ = s.add_output("balance_solids_hold", "kg", OutputRole::kBalanceHold, "solids");
    o_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
    q_heat_ = s.add_quadrature("balance_energy_in", "J", 1e8, OutputRole::kBalanceIn, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_in = c.port(in_, liquid::kMdot);
    const T& mass = c.par(p_mass_);
    // Energy and solute balances divided by M cp and M for scaling.
    c.res(sT_) = c.xd(sT_) - (m_in * (c.port(in_, liquid::kT) - c.x(sT_)) + duty(c) / c.par(p_cp_)) / mass;
    c.res(sW_) = c.xd(sW_) - m_in * (c.port(in_, liquid::kW) - c.x(sW_)) / mass;
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_heat_.i] = duty(c);
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sT_) = c.par(p_t0_);
    c.x(sW_) = c.par(p_w0_);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_duty_) = duty(c);
    c.out(o_water_) = c.par(p_mass_);
    c.out(o_solids_) = c.par(p_mass_) * c.x(sW_);
    c.out(o_energy_) = c.par(p_mass_) * props::liquid_water_enthalpy(c.x(sT_), c.par(p_cp_));
  }

 private:
  template <class T>
  T duty(const Ctx<T>& c) const {
    return c.par(p_u_) * c.par(p_a_) * (c.par(p_tj_) - c.x(sT_));
  }
  ParamId p_mass_, p_cp_, p_u_, p_a_, p_tj_, p_t0_, p_w0_;
  StateId sT_, sW_;
  PortId in_;
  OutputId o_duty_, o_water_, o_solids_, o_energy_;
  QuadId q_heat_;
};

}  // namespace

void register_jacketed_tank() {
  granuflow::units::registry().add(
      "jacketed_tank", "stirred tank at constant hold-up with a jacket at a set temperature (example plugin)",
      [] { return std::make_unique<JacketedTank>(); });
}
