#include "spray_zone.hpp"

#include <type_traits>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/simd_math.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/paper001_spray_zone.hpp"
#include "paper001_streams.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

namespace p1 = kernels::paper001;
namespace def = kernels::paper001::defaults;
namespace holdup = paper001::holdup;

// Work arrays of the closures, per scalar type.
struct Work : Workspace {
  template <class T>
  struct Flow {
    T tau, ws, t_cross;
    bool ws_floored, not_fluidized, tau_floored;
  };
  // Per class, as arrays of each quantity (the flow closures of a double evaluation then run as vector loops).
  template <class T>
  struct Scratch {
    std::vector<T> tau, ws, t_cross, mass, water, m_dep, fwet, xwet;
    void resize(int n) {
      for (auto* v : {&tau, &ws, &t_cross, &mass, &water, &m_dep, &fwet, &xwet}) v->resize(n);
    }
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
};

class SprayZone : public UnitBase<SprayZone> {
 public:
  std::string type() const override { return "spray_zone"; }
  void declare(UnitSpec& s, Settings& settings) override {
    const ParticleSystem& ps = particle_system(s, settings);
    require_water(ps, settings, "the paper-001 spray zone wets the particles");
    pp_ = ps.params();
    grid_ = ps.grid();
    n_ = grid_->size();
    split_ = p1::liquid_split_from_string(settings.get_choice(
        "liquid_split", "class_surface", {"class_surface", "literal"},
        "Eq. (44) weights: N_i tau_i d_i^2 (default, docs/paper001_decisions.md) or tau_i d_i^2 as printed"));
    const std::string t8 = "paper 001, Table 8", t9 = "paper 001, Table 9";
    p_tau1_ = s.add_param({"tau_c1", "-", def::kTauC1, -1.0, 1.0, "Eq. (29) slope on Re", t8});
    p_tau2_ = s.add_param({"tau_c2", "-", def::kTauC2, 0.0, 1.0, "Eq. (29) intercept", t8});
    p_ws1_ = s.add_param({"ws_c1", "-", def::kWsC1, -1.0, 1.0, "Eq. (47) Re^2 coefficient", t9});
    p_ws2_ = s.add_param({"ws_c2", "-", def::kWsC2, -1.0, 1.0, "Eq. (47) Re coefficient", t9});
    p_ws3_ = s.add_param({"ws_c3", "-", def::kWsC3, 0.0, 1.0, "Eq. (47) intercept", t9});
    p_wsf_ =
        s.add_param({"ws_floor", "-", def::kWsFloor, 1e-6, 1.0, "floor of Eq. (47)", "docs/paper001_decisions.md"});
    p_v1_ = s.add_param({"v_c1", "m/s", def::kVelocityC1, -1.0, 1.0, "Eq. (49) Re coefficient", t9});
    p_v2_ = s.add_param({"v_c2", "m/s", def::kVelocityC2, 1e-4, 10.0, "Eq. (49) intercept", t9});
    p_zone_ = s.add_param({"d_zone", "m", def::kSprayZoneDiameter, 1e-3, 10.0, "spray-zone diameter, Eq. (48)", t9});
    p_drop_ = s.add_param({"d_droplet", "m", def::kDropletDiameter, 1e-6, 1e-3, "droplet diameter, Eq. (42)", t9});
    p_rdrop_ =
        s.add_param({"rho_droplet", "kg/m3", def::kDropletDensity, 100.0, 3000.0, "droplet density, Eq. (42)", t9});
    p_hpen_ = s.add_param({"h_pen", "m", def::kPenetrationDepth, 1e-7, 1e-2, "liquid penetration depth, Eq. (57)", t9});
    sDep_ = s.add_states("m_dep", n_, StateKind::Algebraic, "kg/s", 1e-4);
    sFwet_ = s.add_states("fwet", n_, StateKind::Algebraic, "-", 0.1);
    sXwet_ = s.add_states("Xwet", n_, StateKind::Algebraic, "kg/kg", 0.1);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    // Eq. (29)'s residence-time fraction at the faces of the size cells: the shape of the layering growth of the
    // deposited binder solids (docs/binder_granulation.md)
    sTauF_ = s.add_states("tau_face", n_ + 1, StateKind::Algebraic, "-", 0.1);
    liquid_ = s.add_port("liquid", streams::liquid(), PortDir::In);
    bed_ = s.add_port("bed", paper001::holdup_stream(), PortDir::In, n_);
    s.set_port_grid(bed_, grid_->diameter_pivots());
    const PortId out = s.add_port("out", paper001::wetting_stream(), PortDir::Out, n_);
    for (int k = 0; k <= paper001::wetting::T(n_); ++k) s.provide(out, k, sDep_ + k);  // mdot, fwet, Xwet, T
    s.forward(out, paper001::wetting::w(n_), liquid_, liquid::kW);
    for (int f = 0; f <= n_; ++f) s.provide(out, paper001::wetting::tau_face(n_, f), sTauF_ + f);
    s.set_port_grid(out, grid_->diameter_pivots());
    s.set_explicit();  // zero hold-up: its states are evaluated inline, never integrated
    // Class structure for the Jacobian: each class's outputs read its own mass and water, the bed temperature and
    // velocity, the liquid rate, and every class through the sum of the split weights.
    s.set_classes({n_, {sDep_, sFwet_, sXwet_}, {{bed_, holdup::mass(0)}, {bed_, holdup::water(n_, 0)}}});
    r_weights_ = s.add_reduction("split weights");
    o_ws_ = s.add_output("reg_ws_floor", "-", OutputRole::kRegularization);
    o_cap_ = s.add_output("reg_wet_volume_cap", "-", OutputRole::kRegularization);
    o_nofl_ = s.add_output("reg_not_fluidized", "-", OutputRole::kRegularization);
    o_tau0_ = s.add_output("reg_tau_floor", "-", OutputRole::kRegularization);
    o_fwet_ = s.add_output("fwet_mean", "-");
  }

  std::unique_ptr<Workspace> workspace() const override {
    auto w = std::make_unique<Work>();
    w->sd.resize(n_);
    w->sj.resize(n_);
    return w;
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    auto& sc = c.template ws<Work>().template scratch<T>();
    int a = 0, b = 0;
    closures(c, sc, &a, &b);
    for (int i = 0; i < n_; ++i) {
      c.res(sDep_ + i) = c.x(sDep_ + i) - sc.m_dep[i];
      c.res(sFwet_ + i) = c.x(sFwet_ + i) - sc.fwet[i];
      c.res(sXwet_ + i) = c.x(sXwet_ + i) - sc.xwet[i];
    }
    c.res(sT_) = c.x(sT_) - c.port(liquid_, liquid::kT);
    face_residence_times(c);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < n_; ++i) c.x(sDep_ + i) = c.x(sFwet_ + i) = c.x(sXwet_ + i) = T(0.0);
    c.x(sT_) = T(def::kSprayTemperature);
    for (int f = 0; f <= n_; ++f) c.x(sTauF_ + f) = T(0.0);
  }
  // The closures' outputs are the unit's own states (x = f exactly when inlined), so only the flow closures run
  // again here, for their floors; the wetted-volume cap is a function of f_wet alone.
  template <class T>
  void outputs(const Ctx<T>& c) const {
    const T u0 = c.port(bed_, holdup::u0(n_));
    const GasProps<T> g = gas_props(c.port(bed_, holdup::T(n_)));
    const FlowParams<T> q = flow_params(c);
    const T h_pen = c.par(p_hpen_);
    const double* d = grid_->diameter_pivots().data();
    const T* fwet = &c.x(sFwet_);
    int a = 0, b = 0, not_fluidized = 0, tau_floored = 0;
#pragma omp simd reduction(+ : a, b, not_fluidized, tau_floored)  // the closures' floors and caps, counted
    for (int i = 0; i < n_; ++i) {
      const Work::Flow<T> f = class_flow(q, d[i], u0, g);
      a += f.ws_floored, not_fluidized += f.not_fluidized, tau_floored += f.tau_floored;
      b += p1::wetted_volume_ratio(fwet[i], T(d[i]), h_pen) > def::kWetVolumeFractionCap;  // Eq. (57)'s cap
    }
    T mass(0.0), fm(0.0);
    for (int i = 0; i < n_; ++i) {
      mass += c.port(bed_, holdup::mass(i));
      fm += c.port(bed_, holdup::mass(i)) * fwet[i];
    }
    c.out(o_ws_) = T(a);
    c.out(o_cap_) = T(b);
    c.out(o_nofl_) = T(not_fluidized);
    c.out(o_tau0_) = T(tau_floored);
    c.out(o_fwet_) = mass > 0.0 ? T(fm / mass) : T(0.0);
  }

 private:
  // Gas properties for the closures' Reynolds numbers: dry air at the bed temperature (docs/paper001_decisions.md).
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

  // The parameters of the flow closures, read once per evaluation.
  template <class T>
  struct FlowParams {
    T rho_p, wsf, ws1, ws2, ws3, tau1, tau2, v1, v2, zone;
  };
  template <class T>
  FlowParams<T> flow_params(const Ctx<T>& c) const {
    return {c.sh(pp_.rho_p), c.par(p_wsf_),  c.par(p_ws1_), c.par(p_ws2_), c.par(p_ws3_),
            c.par(p_tau1_),  c.par(p_tau2_), c.par(p_v1_),  c.par(p_v2_),  c.par(p_zone_)};
  }
  // DEM-surrogate closures of a class of diameter d, Eqs. (29)-(33), (47)-(49).
  template <class T>
  static Work::Flow<T> class_flow(const FlowParams<T>& q, double d_class, const T& u0, const GasProps<T>& g) {
    const T d(d_class);
    const T umf = kernels::transfer::wen_yu_umf(d, q.rho_p, g.rho, g.mu);  // Eqs. (31)-(33)
    // Eq. (30). A class with u0 < u_mf is not fluidized, outside the range the DEM surrogates were fitted on: it is
    // taken at incipient fluidization (Re = 0), where the fits give a positive velocity and residence time (a
    // negative velocity would make its wetted fraction, and with it aggregation rates, negative).
    const auto re = kernels::floor_at(kernels::transfer::excess_reynolds_number(u0, umf, d, g.nu), T(0.0));
    const auto w = p1::spray_zone_solids_fraction(re.value, q.wsf, q.ws1, q.ws2, q.ws3);  // (47)
    // Eq. (29) turns negative above Re = -c2 / c1 (77 with Table 8): no time in the spray zone, not a negative one
    const auto tau = kernels::floor_at(p1::dimensionless_residence_time(re.value, q.tau1, q.tau2), T(0.0));
    return {tau.value,
            w.value,
            p1::spray_zone_crossing_time(p1::spray_zone_particle_velocity(re.value, q.v1, q.v2),
                                         q.zone),  // Eqs. (48), (49)
            w.active,
            re.active,
            tau.active};
  }

  // The parameters of the liquid split and the wetting closures, read once per evaluation.
  template <class T>
  struct OutputParams {
    T rho_env, d_drop, rho_p, rho_drop, h_pen;
    p1::LiquidSplit split;
  };
  template <class T>
  OutputParams<T> output_params(const Ctx<T>& c) const {
    return {pp_.envelope_density(c.shared), c.par(p_drop_), c.sh(pp_.rho_p), c.par(p_rdrop_), c.par(p_hpen_), split_};
  }
  // Weight of a class (diameter d, pivot volume v) in the liquid split of Eq. (44): N_i tau_i d_i^2 (default) or
  // tau_i d_i^2 (literal).
  template <p1::LiquidSplit S, class T>
  static T split_weight(const OutputParams<T>& o, double d, double v, const T& mass, const T& tau) {
    const T w = tau * d * d;
    if constexpr (S == p1::LiquidSplit::kClassSurface)
      return T(w * mass / (o.rho_env * v));
    else
      return w;
  }
  template <class T>
  static T split_weight(const OutputParams<T>& o, double d, double v, const T& mass, const T& tau) {
    return o.split == p1::LiquidSplit::kClassSurface ? split_weight<p1::LiquidSplit::kClassSurface>(o, d, v, mass, tau)
                                                     : split_weight<p1::LiquidSplit::kLiteral>(o, d, v, mass, tau);
  }

  // Liquid deposited on a class, its wetted surface fraction and wet-spot moisture, given the sum of the split
  // weights; returns whether Eq. (57)'s cap was active. The split is a template argument: chosen inside the class
  // loop, its two cases would keep the loop scalar.
  template <p1::LiquidSplit S, class T>
  static bool class_outputs(const OutputParams<T>& o, double d_class, double v, const T& mass, const T& water,
                            const T& m_liquid, const T& w, const T& weight_sum, const T& tau, const T& ws,
                            const T& t_cross, T* m_dep, T* fwet, T* xwet) {
    const T d(d_class);
    *m_dep = split_weight<S>(o, d_class, v, mass, tau) * m_liquid / weight_sum;  // Eq. (44)
    // Eqs. (43), (45), (46): X_LS = m_dep / (w_s M / t). With the default split, m_dep is proportional to
    // N_i = M_i / m_particle, so the ratio stays finite for an empty class.
    const T x_ls = S == p1::LiquidSplit::kClassSurface
                       ? T(m_liquid * tau * d * d / weight_sum * t_cross / (ws * (o.rho_env * v)))
                       : T(*m_dep * t_cross / (ws * (mass > T(1e-15) ? mass : T(1e-15))));
    // Eq. (42) is linear in X_LS: phi = kappa X_LS
    const T kappa = p1::coating_number(T(1.0), d, o.d_drop, o.rho_p, o.rho_drop);
    const T phi = kappa * x_ls;
    *fwet = p1::surface_coverage(phi);  // Eq. (41)
    // Eq. (57): whether wetted_volume_fraction() caps it (its Limited return would keep this loop scalar)
    const bool capped = p1::wetted_volume_ratio(*fwet, d, o.h_pen) > def::kWetVolumeFractionCap;
    // Eqs. (55)-(56): X_wet - X0 = m_dep / (m_s frac) = X_LS / frac. Uncapped, frac = (h A / V) f_wet, so
    // X_LS / frac = (phi / f_wet) / (kappa h A / V), and phi / f_wet -> 1 + phi / 2 as the spray goes to zero:
    // a droplet's wet spot keeps its moisture however few droplets there are.
    const T g = value_of(phi) < 1e-8 ? T(1.0 + 0.5 * phi) : T(phi / *fwet);
    const T dx = capped ? x_ls : T(g / (kappa * o.h_pen * kernels::sphere_surface(d) / kernels::sphere_volume(d)));
    // Eq. (55): plus the bed moisture X0 of the class. A binder solution (solids fraction w) brings its solids into the
    // wet spot: water (1 - w) m_dep on solids m_s frac + w m_dep, X_wet = (X0 + (1 - w) dx) / (1 + w dx). The binder
    // solid is read as the bed's own solid (maltodextrin: the Gordon-Taylor data of Eq. (54) apply to the mixture;
    // docs/binder_granulation.md). For w = 0 this is dx + X0 to the last bit.
    *xwet = (dx * (1.0 - w) + water / (mass + kMassFloor)) / (1.0 + w * dx);
    return capped;
  }

  // Eq. (29) at the n + 1 cell faces (diameter edges), where the bed's finite-volume layering evaluates its growth.
  template <class T>
  void face_residence_times(const Ctx<T>& c) const {
    const T u0 = c.port(bed_, holdup::u0(n_));
    const GasProps<T> g = gas_props(c.port(bed_, holdup::T(n_)));
    const FlowParams<T> q = flow_params(c);
    const auto& de = grid_->diameter_edges();
    for (int f = 0; f <= n_; ++f) c.res(sTauF_ + f) = c.x(sTauF_ + f) - class_flow(q, de[f], u0, g).tau;
  }

  // All classes; counts the floors and caps that replaced the literal equations.
  template <class T>
  void closures(const Ctx<T>& c, Work::Scratch<T>& sc, int* ws_floored, int* vol_capped) const {
    const T u0 = c.port(bed_, holdup::u0(n_));
    const GasProps<T> g = gas_props(c.port(bed_, holdup::T(n_)));
    const FlowParams<T> q = flow_params(c);
    // Parameters and gas properties in locals, the results in arrays of their own: with doubles a vector loop.
    const double* d = grid_->diameter_pivots().data();
    T *tau = sc.tau.data(), *ws = sc.ws.data(), *t_cross = sc.t_cross.data();
    const int n = n_;  // a local bound: stores through the arrays could change the member n_
    int floored = 0;
#pragma omp simd reduction(+ : floored)
    for (int i = 0; i < n; ++i) {
      const Work::Flow<T> f = class_flow(q, d[i], u0, g);
      tau[i] = f.tau, ws[i] = f.ws, t_cross[i] = f.t_cross;
      floored += f.ws_floored;
    }
    *ws_floored += floored;
    T *mass = sc.mass.data(), *water = sc.water.data();
    for (int i = 0; i < n_; ++i) mass[i] = c.port(bed_, holdup::mass(i)), water[i] = c.port(bed_, holdup::water(n_, i));
    const OutputParams<T> o = output_params(c);
    const double* v = grid_->pivots().data();
    const T sum = c.reduce(r_weights_, n_, [&](int i) { return split_weight(o, d[i], v[i], mass[i], tau[i]); });
    const T m_liquid = c.port(liquid_, liquid::kMdot);
    const T w = c.port(liquid_, liquid::kW);
    T *m_dep = sc.m_dep.data(), *fwet = sc.fwet.data(), *xwet = sc.xwet.data();
    auto outputs = [&](auto split) {
      constexpr p1::LiquidSplit S = decltype(split)::value;
      const int n = n_;
      int capped = 0;
#pragma omp simd reduction(+ : capped)  // in doubles a vector loop (libmvec's expm1, kernels/simd_math.hpp)
      for (int i = 0; i < n; ++i)
        capped += class_outputs<S>(o, d[i], v[i], mass[i], water[i], m_liquid, w, sum, tau[i], ws[i], t_cross[i],
                                   &m_dep[i], &fwet[i], &xwet[i]);
      return capped;
    };
    using Split = p1::LiquidSplit;
    *vol_capped += o.split == Split::kClassSurface ? outputs(std::integral_constant<Split, Split::kClassSurface>{})
                                                   : outputs(std::integral_constant<Split, Split::kLiteral>{});
  }

  int n_ = def::kSizeClasses;
  ParticleParams pp_;
  std::shared_ptr<const kernels::Grid> grid_;
  p1::LiquidSplit split_ = p1::LiquidSplit::kClassSurface;
  ParamId p_tau1_, p_tau2_, p_ws1_, p_ws2_, p_ws3_, p_wsf_, p_v1_, p_v2_, p_zone_, p_drop_, p_rdrop_, p_hpen_;
  StateId sDep_, sFwet_, sXwet_, sT_, sTauF_;
  PortId liquid_, bed_;
  ReductionId r_weights_;
  OutputId o_ws_, o_cap_, o_nofl_, o_tau0_, o_fwet_;
};

}  // namespace

void register_spray_zone(Registry<Unit>& r) {
  r.add("spray_zone", "spray-zone wetting closures of paper 001 (Eqs. 27-35, 40-57)",
        [] { return std::make_unique<SprayZone>(); });
}

}  // namespace granuflow::units
