#include "gas_inlet.hpp"

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"

namespace granuflow::units {
namespace {

enum P { kVdot, kT, kY, kP };
enum S { kMdot, kYs, kTs, kPs, kWaterIn, kEnergyIn };

class GasInlet : public UnitBase<GasInlet> {
 public:
  std::string type() const override { return "gas_inlet"; }
  void declare(UnitSpec& s, Settings& settings) override {
    normal_basis_ = settings.get_choice("flow_basis", "inlet", {"inlet", "normal"},
                                        "volume flow measured at the inlet temperature and pressure (default, "
                                        "docs/paper001_decisions.md) or at 0 degC and 1 atm") == "normal";
    s.add_param({"V_dot", "m3/s", 700.0 / 3600.0, 0.0, 100.0, "air volume flow", "paper 001, Table 1"});
    s.add_param({"T", "K", 333.15, 250.0, 600.0, "air temperature", "paper 001, Table 1"});
    s.add_param(
        {"Y", "kg/kg", 0.005, 0.0, 0.5, "absolute humidity, kg water per kg dry air", "docs/paper001_decisions.md"});
    s.add_param({"p", "Pa", props::kPressureAtm, 5e4, 5e5, "pressure", "docs/paper001_decisions.md"});
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.2);
    s.add_state("Y", StateKind::Algebraic, "kg/kg", 0.01);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("p", StateKind::Algebraic, "Pa", 1e5);
    s.add_state("water_in", StateKind::Differential, "kg", 10.0);
    s.add_state("energy_in", StateKind::Differential, "J", 1e7);
    s.provide_all(s.add_port("out", StreamKind::Gas, PortDir::Out), kMdot);
    s.provide_all(s.add_port("state", StreamKind::Gas, PortDir::Probe), kMdot);
    s.add_output("V_dot", "m3/s");
    s.add_output("balance_water_in", "kg");
    s.add_output("balance_energy_in", "J");
  }
  // Dry-air mass flow of the volume flow V_dot on the chosen basis (docs/paper001_decisions.md: inlet state by
  // default).
  template <class T>
  T dry_mass_flow(const T* p) const {
    const T t_basis = normal_basis_ ? T(props::kT0) : p[kT];
    const T p_basis = normal_basis_ ? T(props::kPressureAtm) : p[kP];
    return p[kVdot] * props::dry_air_partial_density(t_basis, p_basis, p[kY]);
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(kMdot) = c.x_(kMdot) - dry_mass_flow(c.p);
    c.res(kYs) = c.x_(kYs) - c.par(kY);
    c.res(kTs) = c.x_(kTs) - c.par(kT);
    c.res(kPs) = c.x_(kPs) - c.par(kP);
    c.res(kWaterIn) = c.xd(kWaterIn) - c.x_(kMdot) * c.x_(kYs);
    c.res(kEnergyIn) = c.xd(kEnergyIn) - c.x_(kMdot) * props::humid_air_enthalpy(c.x_(kTs), c.x_(kYs));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[kMdot] = dry_mass_flow(c.p);
    c.x0[kYs] = c.p[kY];
    c.x0[kTs] = c.p[kT];
    c.x0[kPs] = c.p[kP];
    c.x0[kWaterIn] = c.x0[kEnergyIn] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    out[0] = c.par(kVdot);
    out[1] = c.x_(kWaterIn);
    out[2] = c.x_(kEnergyIn);
  }

 private:
  bool normal_basis_ = false;
};

}  // namespace

void register_gas_inlet(Registry<Unit>& r) {
  r.add("gas_inlet", "fluidization air: volume flow, temperature, humidity",
        [] { return std::make_unique<GasInlet>(); });
}

}  // namespace granuflow::units
