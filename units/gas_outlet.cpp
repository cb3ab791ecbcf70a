#include "gas_outlet.hpp"

#include "granuflow/properties.hpp"

namespace granuflow::units {
namespace {

// A sink: what leaves is integrated as quadratures, so it adds no unknowns.
class GasOutlet : public UnitBase<GasOutlet> {
 public:
  std::string type() const override { return "gas_outlet"; }
  void declare(UnitSpec& s, Settings&) override {
    in_ = s.add_port("in", streams::gas(), PortDir::In);
    o_t_ = s.add_output("T", "K");
    o_y_ = s.add_output("Y", "kg/kg");
    q_gas_ = s.add_quadrature("dry_gas_out", "kg", 100.0);
    q_water_ = s.add_quadrature("balance_water_out", "kg", 10.0, OutputRole::kBalanceOut, "water");
    q_energy_ = s.add_quadrature("balance_energy_out", "J", 1e7, OutputRole::kBalanceOut, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>&) const {
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    const T& m = c.port(in_, gas::kMdot);
    c.r[q_gas_.i] = m;
    c.r[q_water_.i] = m * c.port(in_, gas::kY);
    c.r[q_energy_.i] = m * props::humid_air_enthalpy(c.port(in_, gas::kT), c.port(in_, gas::kY));
  }
  template <class T>
  void init(InitCtx<T>&) const {}
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_t_) = c.port(in_, gas::kT);
    c.out(o_y_) = c.port(in_, gas::kY);
  }

 private:
  PortId in_;
  OutputId o_t_, o_y_;
  QuadId q_gas_, q_water_, q_energy_;
};

}  // namespace

void register_gas_outlet(Registry<Unit>& r) {
  r.add("gas_outlet", "exhaust gas sink accumulating what leaves", [] { return std::make_unique<GasOutlet>(); });
}

}  // namespace granuflow::units
