#include "liquid_product.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

class LiquidProduct : public UnitBase<LiquidProduct> {
 public:
  std::string type() const override { return "liquid_product"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5,
                 "heat capacity used for the enthalpy account", "water, paper 001, Table 6"});
    s.add_state("mass", StateKind::Differential, "kg", 100.0);
    s.add_state("solute", StateKind::Differential, "kg", 1.0);
    s.add_state("enthalpy", StateKind::Differential, "J", 1e8);
    s.add_port("in", StreamKind::Liquid, PortDir::In);
    s.add_output("balance_water_out", "kg");
    s.add_output("balance_solids_out", "kg");
    s.add_output("balance_energy_out", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m = c.port(0, liquid::kMdot);
    c.res(0) = c.xd(0) - m;
    c.res(1) = c.xd(1) - m * c.port(0, liquid::kW);
    c.res(2) = c.xd(2) - m * props::liquid_water_enthalpy(c.port(0, liquid::kT), c.par(0));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.x0[k] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    for (int k = 0; k < 3; ++k) out[k] = c.x_(k);
  }
};

}  // namespace

void register_liquid_product(Registry<Unit>& r) {
  r.add("liquid_product", "liquid sink accumulating what leaves", [] { return std::make_unique<LiquidProduct>(); });
}

}  // namespace granuflow::units
