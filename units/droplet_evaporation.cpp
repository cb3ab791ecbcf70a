#include "droplet_evaporation.hpp"

#include <cmath>
#include <tuple>

#include "granuflow/properties.hpp"
#include "kernels/drying/paper001_drying.hpp"

namespace granuflow::units {
namespace {

class DropletEvaporation : public UnitBase<DropletEvaporation> {
 public:
  std::string type() const override { return "droplet_evaporation"; }
  void declare(UnitSpec& s, Settings&) override {
    namespace def = kernels::paper001::defaults;
    p_k_ =
        s.add_param({"k_evap", "kg/m2", def::kEvaporationCoefficient, 0.0, 10.0,
                     "evaporation coefficient per droplet surface and unit humidity difference", "paper 001, Table 8"});
    p_d_ = s.add_param({"d_droplet", "m", def::kDropletDiameter, 1e-6, 1e-3, "droplet diameter", "paper 001, Table 9"});
    p_rho_ =
        s.add_param({"rho_l", "kg/m3", def::kLiquidDensity, 500.0, 2000.0, "liquid density", "paper 001, Table 6"});
    p_mult_ = s.add_param({"multiplier", "-", 1.0, 0.0, 100.0, "scales Eq. (66) (option; 1 = as published)",
                           "docs/paper001_decisions.md"});
    sEvap_ = s.add_state("m_evap", StateKind::Algebraic, "kg/s", 1e-4);
    sDep_ = s.add_state("m_dep", StateKind::Algebraic, "kg/s", 1e-3);
    sWdep_ = s.add_state("w_dep", StateKind::Algebraic, "kg/kg", 1.0);
    sWvap_ = s.add_state("w_vap", StateKind::Algebraic, "kg/kg", 1.0);
    spray_ = s.add_port("spray", streams::liquid(), PortDir::In);
    gas_ = s.add_port("gas", streams::gas(), PortDir::In);  // probe of the chamber gas: humidity and temperature
    // Both outlets at the spray's temperature. Only water evaporates: the vapour carries no solids, and the dissolved
    // solids all stay in the deposited droplets, which the evaporation concentrates.
    for (auto [name, m, w] : {std::tuple{"vapour", sEvap_, sWvap_}, std::tuple{"deposit", sDep_, sWdep_}}) {
      const PortId p = s.add_port(name, streams::liquid(), PortDir::Out);
      s.provide(p, liquid::kMdot, m);
      s.forward(p, liquid::kT, spray_, liquid::kT);
      s.provide(p, liquid::kW, w);
    }
    s.set_explicit();
    o_frac_ = s.add_output("evaporated_fraction", "-");
    o_cap_ = s.add_output("reg_evaporation_capped", "-", OutputRole::kRegularization);
  }
  // Eq. (66) with A = droplet surface produced per second (docs/paper001_decisions.md), Y_eq at the gas
  // temperature; returns the uncapped rate.
  template <class T>
  T raw_rate(const Ctx<T>& c) const {
    namespace p1 = kernels::paper001;
    const T& m_l = c.port(spray_, liquid::kMdot);
    const T a = p1::droplet_surface_rate(m_l, c.par(p_rho_), c.par(p_d_));
    const T y_eq = p1::saturation_humidity(c.port(gas_, gas::kT), c.port(gas_, gas::kP)).value;  // Eq. (68), capped
    return c.par(p_mult_) * p1::droplet_evaporation_rate(c.par(p_k_), a, y_eq, c.port(gas_, gas::kY));
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_l = c.port(spray_, liquid::kMdot);
    const T& w = c.port(spray_, liquid::kW);
    const T water = m_l * (1.0 - w);  // = m_l exactly for a water spray (w = 0)
    T m = raw_rate(c);
    // A droplet cannot evaporate more water than it carries, nor condense (the cap is reported when active).
    if (m < T(0.0)) m = T(0.0);
    if (m > water) m = water;
    c.res(sEvap_) = c.x(sEvap_) - m;
    c.res(sDep_) = c.x(sDep_) - (m_l - m);
    // solids fraction of the deposit: all of the sprayed solids in what is left (the spray's own w when nothing is
    // sprayed)
    const T left = m_l - m;
    c.res(sWdep_) = c.x(sWdep_) - (left > 0.0 ? T(m_l * w / left) : T(w));
    c.res(sWvap_) = c.x(sWvap_);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sEvap_) = T(0.0);
    c.x(sDep_) = T(0.0);
    c.x(sWdep_) = c.x(sWvap_) = T(0.0);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    const T& m_l = c.port(spray_, liquid::kMdot);
    const T raw = raw_rate(c);
    const T water = m_l * (1.0 - c.port(spray_, liquid::kW));
    // the share of no spray is undefined, not 0 (NaN in the time series, null in a summary)
    c.out(o_frac_) = m_l > 0.0 ? T(c.x(sEvap_) / m_l) : T(std::nan(""));
    c.out(o_cap_) = (raw < 0.0 || raw > water) && m_l > 0.0 ? T(1.0) : T(0.0);
  }

 private:
  ParamId p_k_, p_d_, p_rho_, p_mult_;
  StateId sEvap_, sDep_, sWdep_, sWvap_;
  PortId spray_, gas_;
  OutputId o_frac_, o_cap_;
};

}  // namespace

void register_droplet_evaporation(Registry<Unit>& r) {
  r.add("droplet_evaporation", "evaporation of spray droplets before deposition (paper 001, Eqs. 66-69)",
        [] { return std::make_unique<DropletEvaporation>(); });
}

}  // namespace granuflow::units
