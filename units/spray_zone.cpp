#include "spray_zone.hpp"

#include <type_traits>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/paper001_spray_zone.hpp"
#include "size_grid_settings.hpp"

namespace granuflow::units {
namespace {

namespace p1 = kernels::paper001;
namespace def = kernels::paper001::defaults;

enum P {
  kTauC1,
  kTauC2,
  kWsC1,
  kWsC2,
  kWsC3,
  kWsFloor,
  kVC1,
  kVC2,
  kDZone,
  kDDrop,
  kRhoDrop,
  kRhoP,
  kRhoEnv,
  kHPen,
  kNParams
};
enum Port { kLiquid, kBed, kOut };

class SprayZone : public UnitBase<SprayZone> {
 public:
  std::string type() const override { return "spray_zone"; }
  void declare(UnitSpec& s, Settings& settings) override {
    d_ = log_spaced_pivots(settings);
    n_ = static_cast<int>(d_.size());
    sd_.resize(n_);
    sj_.resize(n_);
    split_ = p1::liquid_split_from_string(settings.get_choice(
        "liquid_split", "class_surface", {"class_surface", "literal"},
        "Eq. (44) weights: N_i tau_i d_i^2 (default, docs/paper001_decisions.md) or tau_i d_i^2 as printed"));
    s.add_param({"tau_c1", "-", def::kTauC1, -1.0, 1.0, "Eq. (29) slope on Re", "paper 001, Table 8"});
    s.add_param({"tau_c2", "-", def::kTauC2, 0.0, 1.0, "Eq. (29) intercept", "paper 001, Table 8"});
    s.add_param({"ws_c1", "-", def::kWsC1, -1.0, 1.0, "Eq. (47) Re^2 coefficient", "paper 001, Table 9"});
    s.add_param({"ws_c2", "-", def::kWsC2, -1.0, 1.0, "Eq. (47) Re coefficient", "paper 001, Table 9"});
    s.add_param({"ws_c3", "-", def::kWsC3, 0.0, 1.0, "Eq. (47) intercept", "paper 001, Table 9"});
    s.add_param({"ws_floor", "-", def::kWsFloor, 1e-6, 1.0, "floor of Eq. (47)", "docs/paper001_decisions.md"});
    s.add_param({"v_c1", "m/s", def::kVelocityC1, -1.0, 1.0, "Eq. (49) Re coefficient", "paper 001, Table 9"});
    s.add_param({"v_c2", "m/s", def::kVelocityC2, 1e-4, 10.0, "Eq. (49) intercept", "paper 001, Table 9"});
    s.add_param(
        {"d_zone", "m", def::kSprayZoneDiameter, 1e-3, 10.0, "spray-zone diameter, Eq. (48)", "paper 001, Table 9"});
    s.add_param({"d_drop", "m", def::kDropletDiameter, 1e-6, 1e-3, "droplet diameter, Eq. (42)", "paper 001, Table 9"});
    s.add_param(
        {"rho_drop", "kg/m3", def::kDropletDensity, 100.0, 3000.0, "droplet density, Eq. (42)", "paper 001, Table 9"});
    s.add_param({"rho_p", "kg/m3", def::kParticleDensity, 100.0, 5000.0, "particle density in Eqs. (33), (42)",
                 "paper 001, Table 9; docs/paper001_decisions.md"});
    s.add_param({"rho_env", "kg/m3", def::kEnvelopeDensity, 100.0, 5000.0, "envelope density for size <-> mass",
                 "paper 001, Table 6-7: 1545 (1 - 0.3)"});
    s.add_param(
        {"h_pen", "m", def::kPenetrationDepth, 1e-7, 1e-2, "liquid penetration depth, Eq. (57)", "paper 001, Table 9"});
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

  // Gas properties for the closures' Reynolds numbers: dry air at the bed temperature.
  template <class T>
  struct GasProps {
    T rho, mu, nu;
  };
  template <class T>
  GasProps<T> gas_props(const T& t_bed) const {
    const T rho = props::dry_air_density(t_bed, T(props::kPressureAtm));
    const T mu = props::air_viscosity(t_bed);
    return {rho, mu, props::kinematic_viscosity(mu, rho)};
  }

  // DEM-surrogate closures of class i, Eqs. (29)-(33), (47)-(49).
  template <class T>
  struct ClassFlow {
    T tau, ws, t_cross;
    bool ws_floored;
  };
  template <class T>
  ClassFlow<T> class_flow(int i, const T& u0, const GasProps<T>& g, const T* par) const {
    const T d(d_[i]);
    const T umf = kernels::transfer::wen_yu_umf(d, par[kRhoP], g.rho, g.mu);   // Eqs. (31)-(33)
    const T re = kernels::transfer::excess_reynolds_number(u0, umf, d, g.nu);  // Eq. (30)
    const auto w = p1::spray_zone_solids_fraction(re, par[kWsFloor], par[kWsC1], par[kWsC2], par[kWsC3]);  // (47)
    return {p1::dimensionless_residence_time(re, par[kTauC1], par[kTauC2]),                                // Eq. (29)
            w.value,
            p1::spray_zone_crossing_time(p1::spray_zone_particle_velocity(re, par[kVC1], par[kVC2]),
                                         par[kDZone]),  // (48), (49)
            w.active};
  }

  // Weight of class i in the liquid split of Eq. (44): N_i tau_i d_i^2 (default) or tau_i d_i^2 (literal).
  template <class T>
  T split_weight(int i, const T& mass, const ClassFlow<T>& f, const T* par) const {
    const T w = f.tau * d_[i] * d_[i];
    return split_ == p1::LiquidSplit::kClassSurface ? T(w * mass / particle_mass(i, par)) : w;
  }
  template <class T>
  T particle_mass(int i, const T* par) const {
    return par[kRhoEnv] * kernels::sphere_volume(d_[i]);
  }

  // Liquid deposited on class i, its wetted surface fraction and wet-spot moisture, given the sum of the split
  // weights; returns whether Eq. (57)'s cap was active.
  template <class T>
  bool class_outputs(int i, const T& mass, const T& water, const T& m_liquid, const T& weight_sum,
                     const ClassFlow<T>& f, const T* par, T* m_dep, T* fwet, T* xwet) const {
    const T d(d_[i]);
    *m_dep = split_weight(i, mass, f, par) * m_liquid / weight_sum;  // Eq. (44)
    // Eqs. (43), (45), (46): X_LS = m_dep / (w_s M / t). With the default split, m_dep is proportional to
    // N_i = M_i / m_particle, so the ratio stays finite for an empty class.
    T x_ls;
    if (split_ == p1::LiquidSplit::kClassSurface) {
      x_ls = m_liquid * f.tau * d * d / weight_sum * f.t_cross / (f.ws * particle_mass(i, par));
    } else {
      x_ls = *m_dep * f.t_cross / (f.ws * (mass > T(1e-15) ? mass : T(1e-15)));
    }
    // Eq. (42) is linear in X_LS: phi = kappa X_LS
    const T kappa = p1::coating_number(T(1.0), d, par[kDDrop], par[kRhoP], par[kRhoDrop]);
    const T phi = kappa * x_ls;
    *fwet = p1::surface_coverage(phi);                                   // Eq. (41)
    const auto frac = p1::wetted_volume_fraction(*fwet, d, par[kHPen]);  // Eq. (57)
    // Eqs. (55)-(56): X_wet - X0 = m_dep / (m_s frac) = X_LS / frac. Uncapped, frac = (h A / V) f_wet, so
    // X_LS / frac = (phi / f_wet) / (kappa h A / V), and phi / f_wet -> 1 + phi / 2 as the spray goes to zero:
    // a droplet's wet spot keeps its moisture however few droplets there are.
    T dx;
    if (frac.active) {
      dx = x_ls;
    } else {
      const T g = value_of(phi) < 1e-8 ? T(1.0 + 0.5 * phi) : T(phi / *fwet);
      dx = g / (kappa * par[kHPen] * kernels::sphere_surface(d) / kernels::sphere_volume(d));
    }
    *xwet = dx + water / (mass + kMassFloor);  // Eq. (55): plus the bed moisture of the class
    return frac.active;
  }

  // All classes; counts the floors and caps that replaced the literal equations.
  template <class T>
  void closures(const Ctx<T>& c, T* m_dep, T* fwet, T* xwet, int* ws_floored, int* vol_capped) const {
    const T& u0 = c.port(kBed, holdup::u0(n_));
    const GasProps<T> g = gas_props(c.port(kBed, holdup::T(n_)));
    std::vector<ClassFlow<T>>& f = scratch<T>().flow;
    T sum(0.0);
    for (int i = 0; i < n_; ++i) {
      f[i] = class_flow(i, u0, g, c.p);
      *ws_floored += f[i].ws_floored;
      sum += split_weight(i, c.port(kBed, holdup::mass(i)), f[i], c.p);
    }
    const T& m_liquid = c.port(kLiquid, liquid::kMdot);
    for (int i = 0; i < n_; ++i)
      *vol_capped += class_outputs(i, c.port(kBed, holdup::mass(i)), c.port(kBed, holdup::water(n_, i)), m_liquid, sum,
                                   f[i], c.p, &m_dep[i], &fwet[i], &xwet[i]);
  }

  // The exact Jacobian class by class: each class's outputs depend on its mass and water, the bed temperature,
  // u0, the liquid rate and the sum of the split weights, whose derivative with respect to every M_j is known.
  bool jacobian(const Ctx<double>& c, double /*cj*/, JacobianSink& sink) const override {
    using J6 = ceres::Jet<double, 6>;  // directions: M_i, W_i, T_bed, u0, m_liquid, weight sum
    const auto& ports = *c.port_index;
    std::vector<J6> par(kNParams);
    for (int k = 0; k < kNParams; ++k) par[k] = J6(c.par(k));
    const J6 t_bed(c.port(kBed, holdup::T(n_)), 2), u0(c.port(kBed, holdup::u0(n_)), 3);
    const J6 m_liquid(c.port(kLiquid, liquid::kMdot), 4);
    const GasProps<J6> g = gas_props(t_bed);
    std::vector<ClassFlow<J6>> f;
    std::vector<double> dsum_dm(n_);
    J6 sum(0.0);
    for (int j = 0; j < n_; ++j) {
      f.push_back(class_flow(j, u0, g, par.data()));
      const J6 w = split_weight(j, J6(c.port(kBed, holdup::mass(j))), f.back(), par.data());
      sum += w;
      // the weight is linear in M_j (default split) or independent of it (literal)
      dsum_dm[j] = split_ == p1::LiquidSplit::kClassSurface
                       ? value_of(f.back().tau) * d_[j] * d_[j] / particle_mass(j, c.p)
                       : 0.0;
    }
    sum.v[5] = 1.0;  // keeps its dependence on T_bed and u0 and also stands for itself
    const int cols[5] = {0, 0, ports[kBed][holdup::T(n_)], ports[kBed][holdup::u0(n_)], ports[kLiquid][liquid::kMdot]};
    std::vector<double> d_dsum(3 * n_);  // d(output)/d(weight sum), row by row
    std::vector<int> mass_cols(n_);
    for (int i = 0; i < n_; ++i) {
      J6 out[3];
      class_outputs(i, J6(c.port(kBed, holdup::mass(i)), 0), J6(c.port(kBed, holdup::water(n_, i)), 1), m_liquid, sum,
                    f[i], par.data(), &out[0], &out[1], &out[2]);
      const int col_m = ports[kBed][holdup::mass(i)], col_w = ports[kBed][holdup::water(n_, i)];
      for (int r = 0; r < 3; ++r) {
        const int row = r * n_ + i;
        sink.add(row, c.offset + row, 1.0);  // residual x - f
        sink.add(row, col_m, -out[r].v[0]);
        sink.add(row, col_w, -out[r].v[1]);
        for (int d = 2; d < 5; ++d) sink.add(row, cols[d], -out[r].v[d]);
        d_dsum[row] = -out[r].v[5];
      }
      mass_cols[i] = col_m;
    }
    // every output depends on every M_j through the weight sum: one outer product, not 3 N^2 entries
    sink.add_outer(3 * n_, d_dsum.data(), n_, mass_cols.data(), dsum_dm.data());
    sink.add(3 * n_, c.offset + 3 * n_, 1.0);
    sink.add(3 * n_, ports[kLiquid][liquid::kT], -1.0);
    return true;
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    Scratch<T>& w = scratch<T>();
    T* m_dep = w.m_dep.data();
    T* fwet = w.fwet.data();
    T* xwet = w.xwet.data();
    int a = 0, b = 0;
    closures(c, m_dep, fwet, xwet, &a, &b);
    for (int i = 0; i < n_; ++i) {
      c.res(i) = c.x_(i) - m_dep[i];
      c.res(n_ + i) = c.x_(n_ + i) - fwet[i];
      c.res(2 * n_ + i) = c.x_(2 * n_ + i) - xwet[i];
    }
    c.res(3 * n_) = c.x_(3 * n_) - c.port(kLiquid, liquid::kT);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < 3 * n_; ++i) c.x0[i] = T(0.0);
    c.x0[3 * n_] = T(def::kSprayTemperature);
  }
  void report(const Ctx<double>& c, double* out) const override {
    std::vector<double> m_dep(n_), fwet(n_), dx(n_);
    int a = 0, b = 0;
    closures(c, m_dep.data(), fwet.data(), dx.data(), &a, &b);  // dx: wet-spot moistures
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
  // Per scalar type work arrays of the residual, sized once in declare() (one solver evaluates the unit at a time).
  template <class T>
  struct Scratch {
    std::vector<ClassFlow<T>> flow;
    std::vector<T> m_dep, fwet, xwet;
    void resize(int n) {
      flow.resize(n);
      m_dep.resize(n), fwet.resize(n), xwet.resize(n);
    }
  };
  template <class T>
  Scratch<T>& scratch() const {
    if constexpr (std::is_same_v<T, double>)
      return sd_;
    else
      return sj_;
  }
  static constexpr double kMassFloor = holdup::kMassFloor;
  int n_ = def::kSizeClasses;
  std::vector<double> d_;
  p1::LiquidSplit split_ = p1::LiquidSplit::kClassSurface;
  mutable Scratch<double> sd_;
  mutable Scratch<Jet> sj_;
};

}  // namespace

void register_spray_zone(Registry<Unit>& r) {
  r.add("spray_zone", "spray-zone wetting closures of paper 001 (Eqs. 27-35, 40-57)",
        [] { return std::make_unique<SprayZone>(); });
}

}  // namespace granuflow::units
