#include "stirred_tank.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

class StirredTank : public UnitBase<StirredTank> {
 public:
  std::string type() const override { return "stirred_tank"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"mass", "kg", 100.0, 1e-6, 1e9, "liquid hold-up", "operating input"});
    s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5, "heat capacity of the liquid",
                 "water, paper 001, Table 6"});
    s.add_param({"Q", "W", 0.0, -1e9, 1e9, "heating duty", "operating input"});
    s.add_param({"T0", "K", 293.15, 200.0, 700.0, "initial temperature", "initial state (user)"});
    s.add_param({"w0", "kg/kg", 0.0, 0.0, 1.0, "initial solute mass fraction", "initial state (user)"});
    const int m = s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    const int t = s.add_state("T", StateKind::Differential, "K", 300.0);
    const int w = s.add_state("w", StateKind::Differential, "kg/kg", 1.0);
    s.add_port("in", StreamKind::Liquid, PortDir::In);
    const int out = s.add_port("out", StreamKind::Liquid, PortDir::Out);
    s.provide(out, liquid::kMdot, m);
    s.provide(out, liquid::kT, t);
    s.provide(out, liquid::kW, w);
    s.add_state("heat_in", StateKind::Differential, "J", 1e8);
    s.add_output("balance_water_hold", "kg");
    s.add_output("balance_solids_hold", "kg");
    s.add_output("balance_energy_hold", "J");
    s.add_output("balance_energy_in", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_in = c.port(0, liquid::kMdot);
    const T& mass = c.par(0);
    const T& cp = c.par(1);
    c.res(0) = c.x_(0) - m_in;
    // M cp dT/dt = m_in cp (T_in - T) + Q, divided by M cp for scaling
    c.res(1) = c.xd(1) - (m_in * (c.port(0, liquid::kT) - c.x_(1)) + c.par(2) / cp) / mass;
    c.res(2) = c.xd(2) - m_in * (c.port(0, liquid::kW) - c.x_(2)) / mass;
    c.res(3) = c.xd(3) - c.par(2);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[0] = T(0.1);
    c.x0[1] = c.p[3];
    c.x0[2] = c.p[4];
    c.x0[3] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    out[0] = c.par(0);
    out[1] = c.par(0) * c.x_(2);
    out[2] = c.par(0) * props::liquid_water_enthalpy(c.x_(1), c.par(1));
    out[3] = c.x_(3);
  }
};

}  // namespace

void register_stirred_tank(Registry<Unit>& r) {
  r.add("stirred_tank", "heated ideally mixed tank with constant hold-up",
        [] { return std::make_unique<StirredTank>(); });
}

}  // namespace granuflow::units
