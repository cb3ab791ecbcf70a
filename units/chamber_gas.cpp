#include "chamber_gas.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

enum P { kMassGas, kY0, kT0 };
enum S { kW, kH, kY, kT, kMdot, kP };
enum Port { kIn, kEvap, kDrying, kWall, kSolids, kOut, kState };

class ChamberGas : public UnitBase<ChamberGas> {
 public:
  std::string type() const override { return "chamber_gas"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"m_gas", "kg", kernels::paper001::defaults::kGasHoldup, 1e-3, 1e4, "dry-air hold-up of the chamber",
                 "paper 001, Table 7; docs/paper001_decisions.md"});
    s.add_param({"Y0", "kg/kg", 0.005, 0.0, 0.5, "initial humidity", "docs/paper001_decisions.md: gas at inlet state"});
    s.add_param(
        {"T0", "K", 333.15, 250.0, 600.0, "initial temperature", "docs/paper001_decisions.md: gas at inlet state"});
    s.add_state("water", StateKind::Differential, "kg", 0.01);
    s.add_state("enthalpy", StateKind::Differential, "J", 1e5);
    s.add_state("Y", StateKind::Algebraic, "kg/kg", 0.01);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.2);
    s.add_state("p", StateKind::Algebraic, "Pa", 1e5);
    s.add_port("in", StreamKind::Gas, PortDir::In);
    s.add_port("evap", StreamKind::Liquid, PortDir::In, 0, true);    // spray evaporating in the gas
    s.add_port("drying", StreamKind::Vapour, PortDir::In, 0, true);  // vapour from drying particles
    for (const char* name : {"wall", "solids"}) {                    // heat leaving the gas
      const int p = s.add_port(name, StreamKind::Heat, PortDir::Out, 0, true);
      s.provide(p, heat::kT, kT);
    }
    const int out = s.add_port("out", StreamKind::Gas, PortDir::Out);
    const int state = s.add_port("state", StreamKind::Gas, PortDir::Probe);
    for (int port : {out, state}) {
      s.provide(port, gas::kMdot, kMdot);
      s.provide(port, gas::kY, kY);
      s.provide(port, gas::kT, kT);
      s.provide(port, gas::kP, kP);
    }
    s.add_output("relative_humidity", "-");
    s.add_output("balance_water_hold", "kg");
    s.add_output("balance_energy_hold", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_in = c.port(kIn, gas::kMdot);
    const T& y_in = c.port(kIn, gas::kY);
    const T& m_ev = c.port(kEvap, liquid::kMdot);
    const T& m_dr = c.port(kDrying, vapour::kMdot);
    // Eq. (61), paper 001, as a water-mass balance
    c.res(kW) = c.xd(kW) - (m_in * y_in - c.x_(kMdot) * c.x_(kY) + m_ev + m_dr);
    // Eq. (62), paper 001, conservative: inflows at their own enthalpy; the evaporating spray enters as
    // liquid, so the gas supplies its sensible and latent heat (docs/paper001_decisions.md sign)
    c.res(kH) = c.xd(kH) - (m_in * props::humid_air_enthalpy(c.port(kIn, gas::kT), y_in) -
                            c.x_(kMdot) * props::humid_air_enthalpy(c.x_(kT), c.x_(kY)) +
                            m_ev * props::liquid_water_enthalpy(c.port(kEvap, liquid::kT)) +
                            m_dr * props::vapour_enthalpy(c.port(kDrying, vapour::kT)) - c.port(kWall, heat::kQ) -
                            c.port(kSolids, heat::kQ));
    c.res(kY) = c.x_(kW) - c.par(kMassGas) * c.x_(kY);
    c.res(kT) = c.x_(kH) - c.par(kMassGas) * props::humid_air_enthalpy(c.x_(kT), c.x_(kY));  // Eq. (63)
    c.res(kMdot) = c.x_(kMdot) - m_in;                                                       // constant dry-gas hold-up
    c.res(kP) = c.x_(kP) - c.port(kIn, gas::kP);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[kY] = c.p[kY0];
    c.x0[kT] = c.p[kT0];
    c.x0[kW] = c.p[kMassGas] * c.p[kY0];
    c.x0[kH] = c.p[kMassGas] * props::humid_air_enthalpy(c.p[kT0], c.p[kY0]);
    c.x0[kMdot] = T(0.2);
    c.x0[kP] = T(props::kPressureAtm);
  }
  void report(const Ctx<double>& c, double* out) const override {
    out[0] = props::relative_humidity(c.x_(kY), c.x_(kT), c.x_(kP));
    out[1] = c.x_(kW);
    out[2] = c.x_(kH);
  }
};

}  // namespace

void register_chamber_gas(Registry<Unit>& r) {
  r.add("chamber_gas", "well-mixed chamber gas: vapour and enthalpy balances (paper 001, Eqs. 61-63)",
        [] { return std::make_unique<ChamberGas>(); });
}

}  // namespace granuflow::units
