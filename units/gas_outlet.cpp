#include "gas_outlet.hpp"

#include "granuflow/properties.hpp"

namespace granuflow::units {
namespace {

enum S { kGasOut, kWaterOut, kEnergyOut };

class GasOutlet : public UnitBase<GasOutlet> {
 public:
  std::string type() const override { return "gas_outlet"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_state("dry_gas_out", StateKind::Differential, "kg", 100.0);
    s.add_state("water_out", StateKind::Differential, "kg", 10.0);
    s.add_state("energy_out", StateKind::Differential, "J", 1e7);
    s.add_port("in", StreamKind::Gas, PortDir::In);
    s.add_output("T", "K");
    s.add_output("Y", "kg/kg");
    s.add_output("balance_water_out", "kg");
    s.add_output("balance_energy_out", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m = c.port(0, gas::kMdot);
    c.res(kGasOut) = c.xd(kGasOut) - m;
    c.res(kWaterOut) = c.xd(kWaterOut) - m * c.port(0, gas::kY);
    c.res(kEnergyOut) = c.xd(kEnergyOut) - m * props::humid_air_enthalpy(c.port(0, gas::kT), c.port(0, gas::kY));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.x0[k] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    out[0] = c.port(0, gas::kT);
    out[1] = c.port(0, gas::kY);
    out[2] = c.x_(kWaterOut);
    out[3] = c.x_(kEnergyOut);
  }
};

}  // namespace

void register_gas_outlet(Registry<Unit>& r) {
  r.add("gas_outlet", "exhaust gas sink accumulating what leaves", [] { return std::make_unique<GasOutlet>(); });
}

}  // namespace granuflow::units
