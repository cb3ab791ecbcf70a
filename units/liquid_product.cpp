#include "liquid_product.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

// A sink: what arrives is integrated as quadratures, so it adds no unknowns.
class LiquidProduct : public UnitBase<LiquidProduct> {
 public:
  std::string type() const override { return "liquid_product"; }
  void declare(UnitSpec& s, Settings&) override {
    p_cp_ = s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5,
                         "heat capacity used for the enthalpy account", "water, paper 001, Table 6"});
    in_ = s.add_port("in", streams::liquid(), PortDir::In);
    q_mass_ = s.add_quadrature("balance_water_out", "kg", 100.0, OutputRole::kBalanceOut, "water");
    q_solute_ = s.add_quadrature("balance_solids_out", "kg", 1.0, OutputRole::kBalanceOut, "solids");
    q_energy_ = s.add_quadrature("balance_energy_out", "J", 1e8, OutputRole::kBalanceOut, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>&) const {
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    const T& m = c.port(in_, liquid::kMdot);
    c.r[q_mass_.i] = m;
    c.r[q_solute_.i] = m * c.port(in_, liquid::kW);
    c.r[q_energy_.i] = m * props::liquid_water_enthalpy(c.port(in_, liquid::kT), c.par(p_cp_));
  }
  template <class T>
  void init(InitCtx<T>&) const {}

 private:
  ParamId p_cp_;
  PortId in_;
  QuadId q_mass_, q_solute_, q_energy_;
};

}  // namespace

void register_liquid_product(Registry<Unit>& r) {
  r.add("liquid_product", "liquid sink accumulating what leaves", [] { return std::make_unique<LiquidProduct>(); });
}

}  // namespace granuflow::units
