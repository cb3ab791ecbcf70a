#include "spray_zone.hpp"

#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "size_grid_settings.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/paper001_spray_zone.hpp"

namespace granuflow::units {
namespace {

namespace p1 = kernels::paper001;
namespace def = kernels::paper001::defaults;

enum P { kTauC1, kTauC2, kWsC1, kWsC2, kWsC3, kWsFloor, kVC1, kVC2, kDZone, kDDrop, kRhoDrop, kRhoP, kRhoEnv, kHPen };
enum Port { kLiquid, kBed, kOut };

class SprayZone : public UnitBase<SprayZone> {
 public:
  std::string type() const override { return "spray_zone"; }
  void declare(UnitSpec& s, Settings& settings) override {
    d_ = log_spaced_pivots(settings);
    n_ = static_cast<int>(d_.size());
    split_ = p1::liquid_split_from_string(settings.get_choice(
        "liquid_split", "class_surface", {"class_surface", "literal"},
        "Eq. (44) weights: N_i tau_i d_i^2 (default, PAPER001_DECISIONS) or tau_i d_i^2 as printed"));
    s.add_param({"tau_c1", "-", def::kTauC1, -1.0, 1.0, "Eq. (29) slope on Re", "paper 001, Table 8"});
    s.add_param({"tau_c2", "-", def::kTauC2, 0.0, 1.0, "Eq. (29) intercept", "paper 001, Table 8"});
    s.add_param({"ws_c1", "-", def::kWsC1, -1.0, 1.0, "Eq. (47) Re^2 coefficient", "paper 001, Table 9"});
    s.add_param({"ws_c2", "-", def::kWsC2, -1.0, 1.0, "Eq. (47) Re coefficient", "paper 001, Table 9"});
    s.add_param({"ws_c3", "-", def::kWsC3, 0.0, 1.0, "Eq. (47) intercept", "paper 001, Table 9"});
    s.add_param({"ws_floor", "-", def::kWsFloor, 1e-6, 1.0, "floor of Eq. (47)", "PAPER001_DECISIONS"});
    s.add_param({"v_c1", "m/s", def::kVelocityC1, -1.0, 1.0, "Eq. (49) Re coefficient", "paper 001, Table 9"});
    s.add_param({"v_c2", "m/s", def::kVelocityC2, 1e-4, 10.0, "Eq. (49) intercept", "paper 001, Table 9"});
    s.add_param({"d_zone", "m", def::kSprayZoneDiameter, 1e-3, 10.0, "spray-zone diameter, Eq. (48)", "paper 001, Table 9"});
    s.add_param({"d_drop", "m", def::kDropletDiameter, 1e-6, 1e-3, "droplet diameter, Eq. (42)", "paper 001, Table 9"});
    s.add_param({"rho_drop", "kg/m3", def::kDropletDensity, 100.0, 3000.0, "droplet density, Eq. (42)", "paper 001, Table 9"});
    s.add_param({"rho_p", "kg/m3", def::kParticleDensity, 100.0, 5000.0, "particle density in Eqs. (33), (42)",
                 "paper 001, Table 9; PAPER001_DECISIONS"});
    s.add_param({"rho_env", "kg/m3", def::kEnvelopeDensity, 100.0, 5000.0, "envelope density for size <-> mass",
                 "paper 001, Table 6-7: 1545 (1 - 0.3)"});
    s.add_param({"h_pen", "m", def::kPenetrationDepth, 1e-7, 1e-2, "liquid penetration depth, Eq. (57)", "paper 001, Table 9"});
    for (int i = 0; i < n_; ++i) s.add_state("m_dep_" + std::to_string(i), StateKind::Algebraic, "kg/s", 1e-4);
    for (int i = 0; i < n_; ++i) s.add_state("fwet_" + std::to_string(i), StateKind::Algebraic, "-", 0.1);
    for (int i = 0; i < n_; ++i) s.add_state("Xwet_" + std::to_string(i), StateKind::Algebraic, "kg/kg", 0.1);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_port("liquid", StreamKind::Liquid, PortDir::In);
    s.set_port_grid(s.add_port("bed", StreamKind::Holdup, PortDir::In, n_), d_);
    const int out = s.add_port("out", StreamKind::Wetting, PortDir::Out, n_);
    s.provide_all(out, 0);
    s.set_port_grid(out, d_);
    s.set_explicit();  // zero hold-up: its states are evaluated inline, never integrated
    s.add_output("reg_ws_floor", "-");
    s.add_output("reg_wet_volume_cap", "-");
    s.add_output("fwet_mean", "-");
  }

  // Per-class closures; `active` counts the floors and caps that replaced the literal equations.
  template <class T>
  void closures(const Ctx<T>& c, T* m_dep, T* fwet, T* dx_wet, int* ws_floored, int* vol_capped) const {
    const T& t_bed = c.port(kBed, holdup::T(n_));
    const T& u0 = c.port(kBed, holdup::u0(n_));
    // Gas properties for the closures' Reynolds numbers: dry air at the bed temperature.
    const T rho_g = props::dry_air_density(t_bed, T(props::kPressureAtm));
    const T mu = props::air_viscosity(t_bed);
    const T nu = props::kinematic_viscosity(mu, rho_g);
    std::vector<T> tau(n_), d(n_), number(n_), t_cross(n_), ws(n_);
    for (int i = 0; i < n_; ++i) {
      d[i] = T(d_[i]);
      const T umf = kernels::transfer::wen_yu_umf(d[i], c.par(kRhoP), rho_g, mu);  // Eqs. (31)-(33)
      const T re = kernels::transfer::excess_reynolds_number(u0, umf, d[i], nu);    // Eq. (30)
      tau[i] = p1::dimensionless_residence_time(re, c.par(kTauC1), c.par(kTauC2));  // Eq. (29)
      number[i] = c.port(kBed, holdup::mass(i)) / (c.par(kRhoEnv) * kernels::sphere_volume(d[i]));
      const auto w = p1::spray_zone_solids_fraction(re, c.par(kWsFloor), c.par(kWsC1), c.par(kWsC2), c.par(kWsC3));
      ws[i] = w.value;
      *ws_floored += w.active;
      t_cross[i] = p1::spray_zone_crossing_time(p1::spray_zone_particle_velocity(re, c.par(kVC1), c.par(kVC2)),
                                                 c.par(kDZone));  // Eqs. (48), (49)
    }
    const T& m_liquid = c.port(kLiquid, liquid::kMdot);
    p1::distribute_liquid(tau.data(), d.data(), number.data(), n_, m_liquid, split_, m_dep);  // Eq. (44)
    T sum(0.0);
    for (int j = 0; j < n_; ++j) sum += number[j] * tau[j] * d[j] * d[j];
    for (int i = 0; i < n_; ++i) {
      const T m_particle = c.par(kRhoEnv) * kernels::sphere_volume(d[i]);
      // Eqs. (43), (45), (46): X_LS = m_dep / (w_s M / t). With the default split, m_dep is proportional to
      // N_i = M_i / m_particle, so the ratio stays finite for an empty class.
      T x_ls;
      if (split_ == p1::LiquidSplit::kClassSurface) {
        x_ls = m_liquid * tau[i] * d[i] * d[i] / sum * t_cross[i] / (ws[i] * m_particle);
      } else {
        const T m_bed = c.port(kBed, holdup::mass(i));
        x_ls = m_dep[i] * t_cross[i] / (ws[i] * (m_bed > T(1e-15) ? m_bed : T(1e-15)));
      }
      // Eq. (42) is linear in X_LS: phi = kappa X_LS
      const T kappa = p1::coating_number(T(1.0), d[i], c.par(kDDrop), c.par(kRhoP), c.par(kRhoDrop));
      const T phi = kappa * x_ls;
      fwet[i] = p1::surface_coverage(phi);                                           // Eq. (41)
      const auto frac = p1::wetted_volume_fraction(fwet[i], d[i], c.par(kHPen));     // Eq. (57)
      *vol_capped += frac.active;
      // Eqs. (55)-(56): X_wet - X0 = m_dep / (m_s frac) = X_LS / frac. Uncapped, frac = (h A / V) f_wet, so
      // X_LS / frac = (phi / f_wet) / (kappa h A / V), and phi / f_wet -> 1 + phi / 2 as the spray goes to zero:
      // a droplet's wet spot keeps its moisture however few droplets there are.
      if (frac.active) {
        dx_wet[i] = x_ls;
      } else {
        const T g = value_of(phi) < 1e-8 ? T(1.0 + 0.5 * phi) : T(phi / fwet[i]);
        dx_wet[i] = g / (kappa * c.par(kHPen) * kernels::sphere_surface(d[i]) / kernels::sphere_volume(d[i]));
      }
    }
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    std::vector<T> m_dep(n_), fwet(n_), dx(n_);
    int a = 0, b = 0;
    closures(c, m_dep.data(), fwet.data(), dx.data(), &a, &b);
    for (int i = 0; i < n_; ++i) {
      c.res(i) = c.x_(i) - m_dep[i];
      c.res(n_ + i) = c.x_(n_ + i) - fwet[i];
      // Eq. (55): bed moisture of the class plus what the wet spot receives
      const T x0 = c.port(kBed, holdup::water(n_, i)) / (c.port(kBed, holdup::mass(i)) + kMassFloor);
      c.res(2 * n_ + i) = c.x_(2 * n_ + i) - (dx[i] + x0);
    }
    c.res(3 * n_) = c.x_(3 * n_) - c.port(kLiquid, liquid::kT);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < 3 * n_; ++i) c.x0[i] = T(0.0);
    c.x0[3 * n_] = T(283.15);
  }
  void report(const Ctx<double>& c, double* out) const override {
    std::vector<double> m_dep(n_), fwet(n_), dx(n_);
    int a = 0, b = 0;
    closures(c, m_dep.data(), fwet.data(), dx.data(), &a, &b);
    double mass = 0, fm = 0;
    for (int i = 0; i < n_; ++i) {
      mass += c.port(kBed, holdup::mass(i));
      fm += c.port(kBed, holdup::mass(i)) * fwet[i];
    }
    out[0] = a;
    out[1] = b;
    out[2] = mass > 0 ? fm / mass : 0.0;
  }

 private:
  static constexpr double kMassFloor = 1e-12;  // kg: keeps X = W / M finite for an emptied class
  int n_ = def::kSizeClasses;
  std::vector<double> d_;
  p1::LiquidSplit split_ = p1::LiquidSplit::kClassSurface;
};

}  // namespace

void register_spray_zone(Registry<Unit>& r) {
  r.add("spray_zone", "spray-zone wetting closures of paper 001 (Eqs. 27-35, 40-57)",
        [] { return std::make_unique<SprayZone>(); });
}

}  // namespace granuflow::units
