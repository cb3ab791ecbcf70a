#include "spray_nozzle.hpp"

#include "granuflow/errors.hpp"
#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

enum P { kRate, kT, kW, kOn, kOff };
enum S { kMdot, kTs, kWs, kWaterIn, kSolidsIn, kEnergyIn };

class SprayNozzle : public UnitBase<SprayNozzle> {
 public:
  std::string type() const override { return "spray_nozzle"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"mdot", "kg/s", 90e-3 / 60.0, 0.0, 1.0, "liquid spray rate while spraying", "paper 001, Table 1"});
    s.add_param({"T", "K", kernels::paper001::defaults::kSprayTemperature, 273.15, 373.15, "liquid temperature",
                 "paper 001, Table 7"});
    s.add_param({"w", "kg/kg", 0.0, 0.0, 0.9, "dissolved-solids mass fraction of the liquid",
                 "paper 001: water spray (w = 0)"});
    s.add_param({"t_on", "s", 0.0, 0.0, 1e7, "spray start", "paper 001: spraying from the start"});
    s.add_param({"t_off", "s", 3600.0, 0.0, 1e7, "spray stop", "paper 001: 60 min of spraying"});
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 1e-3);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.add_state("water_in", StateKind::Differential, "kg", 1.0);
    s.add_state("solids_in", StateKind::Differential, "kg", 1.0);
    s.add_state("energy_in", StateKind::Differential, "J", 1e6);
    s.provide_all(s.add_port("out", StreamKind::Liquid, PortDir::Out), kMdot);
    s.add_output("balance_water_in", "kg");
    s.add_output("balance_solids_in", "kg");
    s.add_output("balance_energy_in", "J");
  }
  void check(const UnitSpec&, const double* p) const override {
    if (p[kOff] < p[kOn])
      throw ConfigError(violation("t_off", p[kOff], "s", "t_off >= t_on (" + fmt_num(p[kOn]) + " s)"));
  }
  std::vector<double> breakpoints(const double* p) const override { return {p[kOn], p[kOff]}; }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    // On/off decided at the segment start: the integrator stops at t_on and t_off, so a segment never
    // straddles a switch.
    const bool on = c.t_seg >= value_of(c.par(kOn)) && c.t_seg < value_of(c.par(kOff));
    c.res(kMdot) = c.x_(kMdot) - (on ? c.par(kRate) : T(0.0));
    c.res(kTs) = c.x_(kTs) - c.par(kT);
    c.res(kWs) = c.x_(kWs) - c.par(kW);
    c.res(kWaterIn) = c.xd(kWaterIn) - c.x_(kMdot) * (1.0 - c.x_(kWs));
    c.res(kSolidsIn) = c.xd(kSolidsIn) - c.x_(kMdot) * c.x_(kWs);
    // enthalpy above 0 degC; dissolved solids carried at the liquid heat capacity (w = 0 in paper 001)
    c.res(kEnergyIn) = c.xd(kEnergyIn) - c.x_(kMdot) * props::liquid_water_enthalpy(c.x_(kTs));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[kMdot] = value_of(c.p[kOn]) <= 0.0 && value_of(c.p[kOff]) > 0.0 ? c.p[kRate] : T(0.0);
    c.x0[kTs] = c.p[kT];
    c.x0[kWs] = c.p[kW];
    c.x0[kWaterIn] = c.x0[kSolidsIn] = c.x0[kEnergyIn] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    out[0] = c.x_(kWaterIn);
    out[1] = c.x_(kSolidsIn);
    out[2] = c.x_(kEnergyIn);
  }
};

}  // namespace

void register_spray_nozzle(Registry<Unit>& r) {
  r.add("spray_nozzle", "spray liquid source with start and stop times",
        [] { return std::make_unique<SprayNozzle>(); });
}

}  // namespace granuflow::units
