#include "droplet_evaporation.hpp"

#include "granuflow/properties.hpp"
#include "kernels/drying/paper001_drying.hpp"

namespace granuflow::units {
namespace {

enum P { kKEvap, kDDrop, kRhoL, kMult };
enum S { kEvap, kDep, kT, kW };
enum Port { kSpray, kGas, kVapourOut, kDepositOut };

class DropletEvaporation : public UnitBase<DropletEvaporation> {
 public:
  std::string type() const override { return "droplet_evaporation"; }
  void declare(UnitSpec& s, Settings&) override {
    namespace def = kernels::paper001::defaults;
    s.add_param({"k_evap", "kg/m2", def::kEvaporationCoefficient, 0.0, 10.0,
                 "evaporation coefficient per droplet surface and unit humidity difference", "paper 001, Table 8"});
    s.add_param({"d_drop", "m", def::kDropletDiameter, 1e-6, 1e-3, "droplet diameter", "paper 001, Table 9"});
    s.add_param({"rho_l", "kg/m3", def::kLiquidDensity, 500.0, 2000.0, "liquid density", "paper 001, Table 6"});
    s.add_param({"multiplier", "-", 1.0, 0.0, 100.0, "scales Eq. (66) (option; 1 = as published)",
                 "docs/paper001_decisions.md"});
    s.add_state("m_evap", StateKind::Algebraic, "kg/s", 1e-4);
    s.add_state("m_dep", StateKind::Algebraic, "kg/s", 1e-3);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.add_port("spray", StreamKind::Liquid, PortDir::In);
    s.add_port("gas", StreamKind::Gas, PortDir::In);  // probe of the chamber gas: humidity and temperature
    for (auto [name, m] : {std::pair{"vapour", kEvap}, std::pair{"deposit", kDep}}) {
      const int p = s.add_port(name, StreamKind::Liquid, PortDir::Out);
      s.provide(p, liquid::kMdot, m);
      s.provide(p, liquid::kT, kT);
      s.provide(p, liquid::kW, kW);
    }
    s.set_explicit();
    s.add_output("evaporated_fraction", "-");
    s.add_output("reg_evaporation_capped", "-");
  }
  // Eq. (66) with A = droplet surface produced per second (docs/paper001_decisions.md), Y_eq at the gas temperature;
  // returns the uncapped rate.
  template <class T>
  T raw_rate(const Ctx<T>& c) const {
    namespace p1 = kernels::paper001;
    const T& m_l = c.port(kSpray, liquid::kMdot);
    const T a = p1::droplet_surface_rate(m_l, c.par(kRhoL), c.par(kDDrop));
    const T y_eq = p1::saturation_humidity(c.port(kGas, gas::kT), c.port(kGas, gas::kP)).value;  // Eq. (68), capped
    return c.par(kMult) * p1::droplet_evaporation_rate(c.par(kKEvap), a, y_eq, c.port(kGas, gas::kY));
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_l = c.port(kSpray, liquid::kMdot);
    T m = raw_rate(c);
    // A droplet cannot evaporate more than is sprayed, nor condense (the cap is reported when active).
    if (m < T(0.0)) m = T(0.0);
    if (m > m_l) m = m_l;
    c.res(kEvap) = c.x_(kEvap) - m;
    c.res(kDep) = c.x_(kDep) - (m_l - m);
    c.res(kT) = c.x_(kT) - c.port(kSpray, liquid::kT);
    c.res(kW) = c.x_(kW) - c.port(kSpray, liquid::kW);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[kEvap] = T(0.0);
    c.x0[kDep] = T(0.0);
    c.x0[kT] = T(kernels::paper001::defaults::kSprayTemperature);
    c.x0[kW] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override {
    const double m_l = c.port(kSpray, liquid::kMdot), raw = raw_rate(c);
    out[0] = m_l > 0 ? c.x_(kEvap) / m_l : 0.0;
    out[1] = (raw < 0 || raw > m_l) && m_l > 0 ? 1.0 : 0.0;
  }
};

}  // namespace

void register_droplet_evaporation(Registry<Unit>& r) {
  r.add("droplet_evaporation", "evaporation of spray droplets before deposition (paper 001, Eqs. 66-69)",
        [] { return std::make_unique<DropletEvaporation>(); });
}

}  // namespace granuflow::units
