#include "liquid_feed.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

class LiquidFeed : public UnitBase<LiquidFeed> {
 public:
  std::string type() const override { return "liquid_feed"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"mdot", "kg/s", 0.1, 0.0, 1e3, "liquid mass flow", "operating input"});
    s.add_param({"T", "K", 293.15, 200.0, 700.0, "liquid temperature", "operating input"});
    s.add_param({"w", "kg/kg", 0.0, 0.0, 1.0, "dissolved-solids mass fraction", "operating input"});
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.provide_all(s.add_port("out", StreamKind::Liquid, PortDir::Out), 0);
    s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5,
                 "heat capacity for the enthalpy account (above 0 degC)", "water, paper 001, Table 6"});
    // Cumulative amounts fed, so balances close from states rather than from quadrature of outputs.
    s.add_state("mass_in", StateKind::Differential, "kg", 100.0);
    s.add_state("solute_in", StateKind::Differential, "kg", 1.0);
    s.add_state("enthalpy_in", StateKind::Differential, "J", 1e8);
    s.add_output("balance_water_in", "kg");
    s.add_output("balance_solids_in", "kg");
    s.add_output("balance_energy_in", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.res(k) = c.x_(k) - c.par(k);
    c.res(3) = c.xd(3) - c.x_(0);
    c.res(4) = c.xd(4) - c.x_(0) * c.x_(2);
    c.res(5) = c.xd(5) - c.x_(0) * props::liquid_water_enthalpy(c.x_(1), c.par(3));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.x0[k] = c.p[k];
    for (int k = 3; k < 6; ++k) c.x0[k] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    for (int k = 0; k < 3; ++k) out[k] = c.x_(3 + k);
  }
};

}  // namespace

void register_liquid_feed(Registry<Unit>& r) {
  r.add("liquid_feed", "liquid source with set mass flow, temperature and solids fraction",
        [] { return std::make_unique<LiquidFeed>(); });
}

}  // namespace granuflow::units
