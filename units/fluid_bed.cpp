#include "fluid_bed.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/breakage/paper001_breakage_laws.hpp"
#include "kernels/discretization/grid.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/drying/paper001_drying.hpp"
#include "kernels/limited.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/paper001_spray_zone.hpp"
#include "size_grid_settings.hpp"

namespace granuflow::units {
namespace {

namespace p1 = kernels::paper001;
namespace def = kernels::paper001::defaults;
namespace tr = kernels::transfer;

enum P {
  kBedMass,
  kX0,
  kD50,
  kSigma,
  kTS0,
  kRhoS,
  kEps,
  kCpS,
  kCpL,
  kABed,  // bed and material
  kLnBeta0,
  kTauSpray,
  kStickyOffset,
  kStickySlope,
  kGtK,
  kTgL,
  kTgS,
  kVVessel,  // agglomeration
  kKBreak,
  kDMinBreak,
  kFMat,
  kEMin,
  kQFrag,
  kDFragMin,  // breakage
  kXcr,
  kShCorr,
  kBetMm,
  kBetN,
  kDv,
  kLambda,
  kNParams  // drying, transfer
};
enum Port { kWet, kGasProbe, kInletProbe, kVapourOut, kHeatIn, kState };

enum class Aggregation { kNone, kGlassTransition, kConstant };

class FluidBed : public UnitBase<FluidBed> {
 public:
  std::string type() const override { return "fluid_bed"; }

  void declare(UnitSpec& s, Settings& st) override {
    const std::vector<double> d = log_spaced_pivots(st);
    n_ = static_cast<int>(d.size());
    const std::string agg = st.get_choice("aggregation", "glass_transition", {"glass_transition", "constant", "none"},
                                          "agglomeration kernel: paper 001 Eqs. (36)-(57), size-independent, or off");
    agg_ = agg == "glass_transition" ? Aggregation::kGlassTransition
           : agg == "constant"       ? Aggregation::kConstant
                                     : Aggregation::kNone;
    breakage_ = st.get_choice("breakage", "vogel_peukert", {"vogel_peukert", "none"},
                              "breakage: paper 001 Eqs. (90)-(93), or off") == "vogel_peukert";
    size_unit_ = p1::breakage_size_unit_from_string(st.get_choice(
        "breakage_size_unit", "um", {"um", "mm"}, "unit of d in Eq. (92) (docs/paper001_decisions.md: um)"));
    per_volume_ = st.get_choice("beta0_basis", "absolute", {"absolute", "per_m3"},
                                "beta0 for absolute particle numbers (default) or per m^3 of vessel") == "per_m3";
    grid_ = std::make_unique<kernels::Grid>(kernels::Grid::from_diameter_pivots(d));
    sd_.resize(n_);
    sj_.resize(n_);

    const std::string t7 = "paper 001, Table 7", t6 = "paper 001, Table 6", t9 = "paper 001, Table 9",
                      t10 = "paper 001, Table 10", t8 = "paper 001, Table 8", dec = "docs/paper001_decisions.md";
    const ParamSpec specs[kNParams] = {
        {"bed_mass", "kg", 15.0, 1e-3, 1e4, "initial wet bed mass", "paper 001, section 3.1.3"},
        {"X0", "kg/kg", 0.03 / 0.97, 0.0, 1.0, "initial moisture, dry basis", dec},
        {"d50_0", "m", 200e-6, 1e-6, 1e-2, "initial mass median diameter (log-normal in mass)", dec},
        {"sigma_0", "-", 1.5, 1.01, 5.0, "initial geometric standard deviation", dec},
        {"T0", "K", 333.15, 250.0, 500.0, "initial solids temperature", dec},
        {"rho_s", "kg/m3", def::kSolidSkeletalDensity, 100.0, 5000.0, "skeletal density", t6},
        {"eps_intra", "-", def::kIntraParticleVoidFraction, 0.0, 0.9, "intra-particle void fraction", t7},
        {"cp_s", "J/(kg K)", def::kSolidCp, 100.0, 1e4, "solid heat capacity", t6},
        {"cp_l", "J/(kg K)", def::kLiquidCp, 100.0, 1e4, "liquid heat capacity", t6},
        {"A_bed", "m2", def::kBedArea, 1e-4, 100.0, "bed cross-section (A_inlet)", t6},
        {"ln_beta0", "-", def::kLnBeta0, -60.0, 10.0,
         "ln of the agglomeration rate constant (beta0 in 1/s with d in m)", t9},
        {"tau_spray", "-", def::kTauSpray, 0.0, 1.0, "fraction of particles in the spray zone, Eq. (37)", t9},
        {"sticky_offset", "K", def::kStickyOffset, 0.0, 200.0, "sticky point above Tg, Eq. (53)", t9},
        {"sticky_slope", "K", def::kStickySlope, 0.1, 200.0, "width of the sticky transition, Eq. (53)", t9},
        {"gt_k", "-", def::kGordonTaylorK, 0.01, 100.0, "Gordon-Taylor constant, Eq. (54)", t9},
        {"Tg_liquid", "K", def::kTgLiquid, 50.0, 400.0, "glass transition of water", t9},
        {"Tg_solid", "K", def::kTgSolid, 200.0, 700.0, "glass transition of maltodextrin", t9},
        {"V_vessel", "m3", def::kEquipmentVolume, 1e-3, 1e3, "vessel volume (beta0_basis = per_m3)", t6},
        {"k_break", "1/s", def::kBreakageRate, 0.0, 10.0, "breakage rate constant, Eq. (92)", t10},
        {"d_min_break", "m", def::kBreakageDiameterMin, 1e-7, 1e-2, "minimum breakage diameter, Eq. (92)", t10},
        {"f_mat", "-", def::kMaterialParameter, 0.0, 100.0, "material parameter, Eq. (92)", t10},
        {"E_min", "J/kg", def::kBreakageEnergyMin, 0.0, 100.0, "mass-based threshold energy, Eq. (92)", t10},
        {"q_frag", "-", def::kFragmentExponent, 0.01, 10.0, "fragment power-law exponent, Eq. (93)", t10},
        {"d_frag_min", "m", def::kFragmentDiameterMin, 1e-7, 1e-2, "minimum fragment size, Eq. (93)", t10},
        {"X_cr", "kg/kg", def::kCriticalMoisture, 1e-4, 1.0, "critical moisture content, Eq. (80)", t8},
        {"sh_corr", "-", def::kBulkSherwoodCorrection, 1e-3, 100.0, "bulk Sherwood correction, Eq. (74)", t8},
        {"bet_mm", "kg/kg", def::kBetMonolayer, 0.0, 1.0, "BET monolayer moisture, Eq. (81)", t8},
        {"bet_n", "-", def::kBetN, 1.0, 100.0, "BET n, Eq. (81)", t8},
        {"D_v", "m2/s", def::kVapourDiffusivity, 1e-7, 1e-3, "vapour diffusivity", t6},
        {"lambda_g", "W/(m K)", def::kGasConductivity, 1e-3, 1.0, "gas thermal conductivity", t6},
    };
    for (const auto& p : specs) s.add_param(p);

    // Tolerance scales of the class inventories are those of the whole bed (about 10 kg solids, 0.5 kg water):
    // an emptied class needs no more absolute accuracy than the bed it belongs to.
    for (int i = 0; i < n_; ++i) s.add_state("M_" + std::to_string(i), StateKind::Differential, "kg", 10.0);
    for (int i = 0; i < n_; ++i) s.add_state("W_" + std::to_string(i), StateKind::Differential, "kg", 0.5);
    sH_ = s.add_state("H", StateKind::Differential, "J", 1e6);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sU0_ = s.add_state("u0", StateKind::Algebraic, "m/s", 1.0);
    sVap_ = s.add_state("m_vap", StateKind::Algebraic, "kg/s", 1e-3);
    sQ_ = s.add_state("Q", StateKind::Algebraic, "W", 1e3);
    // cumulative mass of aggregates formed beyond the top pivot (each kept in the top class with its mass)
    sTop_ = s.add_state("mass_through_top", StateKind::Differential, "kg", 1.0);

    s.set_port_grid(s.add_port("wetting", StreamKind::Wetting, PortDir::In, n_, true), d);
    s.add_port("gas", StreamKind::Gas, PortDir::In);
    s.add_port("inlet", StreamKind::Gas, PortDir::In);
    const int vap = s.add_port("vapour", StreamKind::Vapour, PortDir::Out, 0, true);
    s.provide(vap, vapour::kMdot, sVap_);
    s.provide(vap, vapour::kT, sT_);
    s.provide(s.add_port("heat", StreamKind::Heat, PortDir::In, 0, true), heat::kQ, sQ_);
    const int probe = s.add_port("state", StreamKind::Holdup, PortDir::Probe, n_);
    s.set_port_grid(probe, d);
    for (int i = 0; i < n_; ++i) {
      s.provide(probe, holdup::mass(i), i);
      s.provide(probe, holdup::water(n_, i), n_ + i);
    }
    s.provide(probe, holdup::T(n_), sT_);
    s.provide(probe, holdup::u0(n_), sU0_);

    for (const char* o : {"d10", "d50", "d90"}) o_quantiles_.push_back(s.add_output(o, "m"));
    o_moisture_ = s.add_output("moisture", "kg/kg");
    o_moisture_wet_ = s.add_output("moisture_wet", "kg/kg");
    o_particles_ = s.add_output("particles", "-");
    o_top_ = s.add_output("top_class_fraction", "-");  // mass fraction in the top class: the grid saturates
    o_reg_eta_ = s.add_output("reg_eta", "-");
    o_reg_a_ = s.add_output("reg_activity_cap", "-");  // water activity < 0.99 in Eq. (81), p_sat < 0.9 p in (72)
    o_balance_ = s.add_output("balance_water_hold", "kg");
    s.add_output("balance_solids_hold", "kg");
    s.add_output("balance_energy_hold", "J");
    o_psd_ = s.add_output("psd_d_0", "m");
    for (int i = 1; i < n_; ++i) s.add_output("psd_d_" + std::to_string(i), "m");
    for (int i = 0; i < n_; ++i) s.add_output("psd_m_" + std::to_string(i), "kg");
    // The further characteristic diameters of paper 001, Table 5 (calibration observables).
    for (const char* o : {"d5", "d16", "d25", "d75", "d84", "d95"}) o_quantiles_.push_back(s.add_output(o, "m"));
  }

  void configure(const UnitSpec&, const double* p) override {
    const auto& x = grid_->pivots();
    const auto& dp = grid_->diameter_pivots();
    // Aggregation targets of every pair (mass-based fixed pivot): the aggregate of volume x_j + x_k is split
    // between the pivots around it keeping number and mass; beyond the top pivot it stays in the top class
    // with its mass (docs/paper001_decisions.md), and that mass is tracked.
    pairs_.clear();
    for (int j = 0; j < n_; ++j)
      for (int k = j; k < n_; ++k) {
        const double v = x[j] + x[k];
        Pair pr{j, k, -1, 0.0, v >= x[n_ - 1]};
        if (pr.beyond) {
          pr.a = n_ - 1;
          pr.frac_upper = 0.0;  // all mass to the top class
        } else {
          int a = 0;
          while (x[a + 1] <= v) ++a;
          const double nu = (v - x[a]) / (x[a + 1] - x[a]);
          pr.a = a;
          // mass fractions of the aggregate landing on a and a + 1
          pr.frac_upper = nu * x[a + 1] / v;
        }
        pairs_.push_back(pr);
      }
    // Eq. (37) per pair depends on parameters only: once per run for residuals and Jacobians
    cf_.resize(pairs_.size());
    for (size_t q = 0; q < pairs_.size(); ++q)
      cf_[q] = p1::collision_frequency(dp[pairs_[q].j], dp[pairs_[q].k], p[kLnBeta0], p[kTauSpray]);
    particle_mass_.resize(n_);
    surface_per_mass_.resize(n_);
    shape_.resize(n_);
    frag_.resize(size_t(n_) * n_);
    material_tables(p, particle_mass_.data(), surface_per_mass_.data(), shape_.data(), frag_.data());
  }

  // Tables fixed by the parameters: particle mass and surface per mass of each class, the breakage selection
  // rate per unit k_break (Eq. (92)) and the mass split of a parent's fragments over the cells below it (Eq. (93)
  // read as a cumulative mass fraction; fines below the first edge go to class 0).
  template <class T>
  void material_tables(const T* p, T* pm, T* spm, T* shape, T* frag) const {
    const auto& x = grid_->pivots();
    const auto& de = grid_->diameter_edges();
    const auto& dp = grid_->diameter_pivots();
    for (int i = 0; i < n_; ++i) {
      pm[i] = p[kRhoS] * (1.0 - p[kEps]) * x[i];
      spm[i] = kernels::sphere_surface(dp[i]) / pm[i];
    }
    for (int k = 0; k < n_; ++k) {
      shape[k] = p1::breakage_rate(T(dp[k]), size_unit_, T(1.0), p[kDMinBreak], p[kFMat], p[kEMin]);
      T below(0.0);
      for (int c = 0; c < n_; ++c) {
        if (c > k) {
          frag[size_t(c) * n_ + k] = T(0.0);
          continue;
        }
        const double upper = c == k ? dp[k] : de[c + 1];
        const T b = p1::cumulative_fragment_distribution(T(upper), T(dp[k]), p[kQFrag], p[kDFragMin]);
        frag[size_t(c) * n_ + k] = b - below;
        below = b;
      }
      frag[size_t(k) * n_ + k] -= 1.0;  // the parent leaves class k
    }
  }
  // The tables for the residual: cached in configure() for doubles; Jets recompute them, so that sensitivities
  // to rho_s, eps_intra and the breakage parameters carry through (as for cf_).
  template <class T>
  struct Tables {
    const T *pm, *spm, *shape, *frag;
  };
  template <class T>
  Tables<T> tables(const T* p) const {
    if constexpr (std::is_same_v<T, double>) {
      return {particle_mass_.data(), surface_per_mass_.data(), shape_.data(), frag_.data()};
    } else {
      Scratch<T>& w = scratch<T>();
      material_tables(p, w.pm.data(), w.spm.data(), w.shape.data(), w.frag.data());
      return {w.pm.data(), w.spm.data(), w.shape.data(), w.frag.data()};
    }
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    Scratch<T>& w = scratch<T>();
    std::fill(w.dM.begin(), w.dM.end(), T(0.0));
    std::fill(w.dW.begin(), w.dW.end(), T(0.0));
    T* dM = w.dM.data();
    T* dW = w.dW.data();
    T* X = w.X.data();
    T* dry = w.dry.data();
    for (int i = 0; i < n_; ++i) X[i] = moisture(c, i);
    const T& t_s = c.x_(sT_);
    const Tables<T> tb = tables(c.p);
    T beyond(0.0);
    if (agg_ != Aggregation::kNone) aggregation(c, X, tb.pm, dM, dW, &beyond);
    if (breakage_) {
      for (int k = 0; k < n_; ++k) {
        // Eq. (92) selection times the fragment mass split: linear in M and W (fragments keep the parent's
        // moisture, docs/paper001_decisions.md)
        const T sk = c.par(kKBreak) * tb.shape[k];
        for (int cl = 0; cl <= k; ++cl) {
          const T& f = tb.frag[size_t(cl) * n_ + k];
          dM[cl] += sk * f * c.x_(k);
          dW[cl] += sk * f * c.x_(n_ + k);
        }
      }
    }
    int reg_eta = 0, reg_a = 0;
    T q_vs(0.0);
    transfer(c, tb, dry, &q_vs, &reg_eta, &reg_a);
    T m_vap(0.0), h_dep(0.0);
    const bool wet = c.connected(kWet);
    for (int i = 0; i < n_; ++i) {
      const T dep = wet ? c.port(kWet, wetting::mdot(i)) : T(0.0);
      m_vap += dry[i];
      c.res(i) = c.xd(i) - dM[i];                             // Eq. (20), paper 001, per class in mass
      c.res(n_ + i) = c.xd(n_ + i) - (dep - dry[i] + dW[i]);  // Eq. (58), paper 001, as water mass per class
      h_dep += dep;
    }
    const T t_liq = wet ? c.port(kWet, wetting::T(n_)) : T(props::kT0);
    // Eq. (59), paper 001, conservative: deposited liquid at its enthalpy, drying vapour leaves at h_v(T_S)
    // (the particle supplies the latent heat), gas-solid heat transfer Q.
    c.res(sH_) = c.xd(sH_) - (h_dep * props::liquid_water_enthalpy(t_liq, c.par(kCpL)) -
                              c.x_(sVap_) * props::vapour_enthalpy(t_s) + c.x_(sQ_));
    T heat_capacity(0.0);
    for (int i = 0; i < n_; ++i) heat_capacity += c.x_(i) * c.par(kCpS) + c.x_(n_ + i) * c.par(kCpL);
    c.res(sT_) = c.x_(sH_) - heat_capacity * (t_s - props::kT0);  // Eq. (60), paper 001
    c.res(sU0_) = c.x_(sU0_) - inlet_velocity(c);
    c.res(sVap_) = c.x_(sVap_) - m_vap;
    c.res(sQ_) = c.x_(sQ_) - q_vs;
    c.res(sTop_) = c.xd(sTop_) - beyond;
    return Status::kOk;
  }

  template <class T>
  void init(InitCtx<T>& c) const {
    const T dry = c.p[kBedMass] / (1.0 + c.p[kX0]);
    // Initial log-normal mass distribution over the cells, tails beyond the grid folded into the end classes;
    // in T, so that initial sensitivities to d50_0 and sigma_0 are exact.
    const auto& de = grid_->diameter_edges();
    auto cdf = [&](int e) {
      using std::erfc, std::log;
      return T(0.5 * erfc(-log(de[e] / c.p[kD50]) / (log(c.p[kSigma]) * std::sqrt(2.0))));
    };
    T heat_capacity(0.0), below(0.0);
    for (int i = 0; i < n_; ++i) {
      const T upto = i == n_ - 1 ? T(1.0) : cdf(i + 1);
      c.x0[i] = dry * (upto - below);
      below = upto;
      c.x0[n_ + i] = c.x0[i] * c.p[kX0];
      heat_capacity += c.x0[i] * c.p[kCpS] + c.x0[n_ + i] * c.p[kCpL];
    }
    c.x0[sT_] = c.p[kTS0];
    c.x0[sH_] = heat_capacity * (c.p[kTS0] - props::kT0);
    c.x0[sU0_] = T(0.5);
    c.x0[sVap_] = T(0.0);
    c.x0[sQ_] = T(0.0);
    c.x0[sTop_] = T(0.0);
  }

  // The aggregation term of the M and W rows, differentiated pair by pair: each pair's event rate depends on
  // at most seven variables (both masses, wetted fractions and wet-spot moistures, and T_S), so this part of
  // the exact Jacobian costs O(N^2) instead of O(N^2) per AD direction.
  void aggregation_jacobian(const Ctx<double>& c, JacobianSink& sink) const {
    if (agg_ == Aggregation::kNone) return;
    const bool wet = c.connected(kWet);
    if (agg_ == Aggregation::kGlassTransition && !wet) return;  // no wetted surface: beta = 0
    const auto& ports = *c.port_index;
    std::vector<double> number(n_), X(n_), fwet(n_, 0.0), sticky(n_, 0.0), ds_dx(n_, 0.0), ds_dt(n_, 0.0);
    for (int i = 0; i < n_; ++i) {
      number[i] = c.x_(i) / particle_mass_[i];
      X[i] = moisture(c, i);
      if (agg_ == Aggregation::kGlassTransition) {
        using J2 = ceres::Jet<double, 2>;  // d/dXwet, d/dT_S
        fwet[i] = c.port(kWet, wetting::fwet(n_, i));
        const J2 xw(c.port(kWet, wetting::Xwet(n_, i)), 0), ts(c.x_(sT_), 1);
        const J2 tg = p1::gordon_taylor(xw, J2(c.par(kGtK)), J2(c.par(kTgL)), J2(c.par(kTgS)));
        const J2 s = p1::sticky_probability(ts, tg, J2(c.par(kStickySlope)), J2(c.par(kStickyOffset)));
        sticky[i] = s.a;
        ds_dx[i] = s.v[0];
        ds_dt[i] = s.v[1];
      }
    }
    const double scale = per_volume_ ? 1.0 / c.par(kVVessel) : 1.0;
    const double beta_constant = agg_ == Aggregation::kConstant ? std::exp(c.par(kLnBeta0)) : 0.0;
    const int col_t = c.offset + sT_;
    auto col_m = [&](int i) { return c.offset + i; };
    auto col_w = [&](int i) { return c.offset + n_ + i; };
    for (size_t q = 0; q < pairs_.size(); ++q) {
      const Pair& pr = pairs_[q];
      const int j = pr.j, k = pr.k;
      const double mj = particle_mass_[j], mk = particle_mass_[k], s = (j == k ? 0.5 : 1.0) * scale;
      double beta, db_dfj = 0, db_dfk = 0, db_dxj = 0, db_dxk = 0, db_dt = 0;
      if (agg_ == Aggregation::kGlassTransition) {
        const double cf = cf_[q];
        const double pg = 1.0 - (1.0 - fwet[j]) * (1.0 - fwet[k]);
        const double pp = 1.0 - (1.0 - sticky[j]) * (1.0 - sticky[k]);
        beta = cf * pg * pp;
        db_dfj = cf * pp * (1.0 - fwet[k]);
        db_dfk = cf * pp * (1.0 - fwet[j]);
        db_dxj = cf * pg * (1.0 - sticky[k]) * ds_dx[j];
        db_dxk = cf * pg * (1.0 - sticky[j]) * ds_dx[k];
        db_dt = cf * pg * ((1.0 - sticky[k]) * ds_dt[j] + (1.0 - sticky[j]) * ds_dt[k]);
      } else {
        beta = beta_constant;
      }
      const double nn = s * number[j] * number[k];
      const double e = beta * nn;  // events per second
      // dE/d(column) for the pair's variables
      struct D {
        int col;
        double v;
      };
      D de[7];
      int nd = 0;
      de[nd++] = {col_m(j), s * beta * number[k] / mj};
      de[nd++] = {col_m(k), s * beta * number[j] / mk};
      if (agg_ == Aggregation::kGlassTransition) {
        de[nd++] = {ports[kWet][wetting::fwet(n_, j)], db_dfj * nn};
        de[nd++] = {ports[kWet][wetting::fwet(n_, k)], db_dfk * nn};
        de[nd++] = {ports[kWet][wetting::Xwet(n_, j)], db_dxj * nn};
        de[nd++] = {ports[kWet][wetting::Xwet(n_, k)], db_dxk * nn};
        de[nd++] = {col_t, db_dt * nn};
      }
      // rates per event: mass and water coefficients of the touched rows (residual = xdot - rate)
      const double up = pr.frac_upper, m_agg = mj + mk, w_agg = mj * X[j] + mk * X[k];
      struct R {
        int row;
        double cm, cw;
      };
      const R rows[4] = {{j, -mj, -mj * X[j]},
                         {k, -mk, -mk * X[k]},
                         {pr.a, (1 - up) * m_agg, (1 - up) * w_agg},
                         {pr.a + 1, up * m_agg, up * w_agg}};
      const int nrows = up > 0 ? 4 : 3;
      for (int r = 0; r < nrows; ++r)
        for (int t = 0; t < nd; ++t) {
          sink.add(rows[r].row, de[t].col, -rows[r].cm * de[t].v);
          sink.add(n_ + rows[r].row, de[t].col, -rows[r].cw * de[t].v);
        }
      if (pr.beyond)
        for (int t = 0; t < nd; ++t) sink.add(sTop_, de[t].col, -m_agg * de[t].v);
      // water rows through X_j = W_j / (M_j + floor) and X_k
      for (auto [cls, mc] : {std::pair{j, mj}, std::pair{k, mk}}) {
        const double inv = 1.0 / (c.x_(cls) + kMassFloor);
        const double dx_dw = inv, dx_dm = -X[cls] * inv;
        const double coef[3] = {-e * mc, (1 - up) * e * mc, up * e * mc};  // d(rate of W rows) / dX_cls
        const int wrows[3] = {cls, pr.a, pr.a + 1};
        for (int r = 0; r < (up > 0 ? 3 : 2); ++r) {
          sink.add(n_ + wrows[r], col_w(cls), -coef[r] * dx_dw);
          sink.add(n_ + wrows[r], col_m(cls), -coef[r] * dx_dm);
        }
      }
    }
  }

  // The exact Jacobian, assembled from small pieces instead of AD over all ~5N local columns: aggregation pair
  // by pair, breakage as its constant matrix, drying and heat transfer class by class with local AD over the
  // eight variables each class depends on (M_i, W_i, T_S, u0, Y, p, T_gas and the bed's area ratio, whose
  // derivative with respect to every M_j is a constant).
  bool jacobian(const Ctx<double>& c, double cj, JacobianSink& sink) const override {
    using J8 = ceres::Jet<double, 8>;
    using J4 = ceres::Jet<double, 4>;
    const auto& ports = *c.port_index;
    auto col_m = [&](int i) { return c.offset + i; };
    auto col_w = [&](int i) { return c.offset + n_ + i; };
    const int col_ts = c.offset + sT_;
    for (int i = 0; i < n_; ++i) sink.add(i, col_m(i), cj), sink.add(n_ + i, col_w(i), cj);
    sink.add(sH_, c.offset + sH_, cj);
    sink.add(sTop_, c.offset + sTop_, cj);
    aggregation_jacobian(c, sink);
    if (breakage_)
      for (int k = 0; k < n_; ++k)
        for (int cl = 0; cl <= k; ++cl) {
          const double v = c.par(kKBreak) * shape_[k] * frag_[size_t(cl) * n_ + k];
          sink.add(cl, col_m(k), -v);
          sink.add(n_ + cl, col_w(k), -v);
        }
    // drying (W rows, m_vap row) and heat transfer (Q row)
    std::vector<J8> par(kNParams);
    for (int k = 0; k < kNParams; ++k) par[k] = J8(c.par(k));
    const int cols[7] = {
        0, 0, col_ts, c.offset + sU0_, ports[kGasProbe][gas::kY], ports[kGasProbe][gas::kP], ports[kGasProbe][gas::kT]};
    const GasSide<J8> g =
        gas_side(J8(c.x_(sT_), 2), J8(c.port(kGasProbe, gas::kT), 6), J8(c.port(kGasProbe, gas::kY), 4),
                 J8(c.port(kGasProbe, gas::kP), 5), J8(c.x_(sU0_), 3),
                 J8(value_of(area_ratio(c, surface_per_mass_.data())), 7), par.data());
    std::vector<double> ddry_dratio(n_);
    double dvap_dratio = 0, dq_dratio = 0;
    for (int i = 0; i < n_; ++i) {
      J8 dry, q;
      class_transfer(i, J8(c.x_(i), 0), J8(c.x_(n_ + i), 1), J8(particle_mass_[i]), g, par.data(), &dry, &q);
      for (auto [row, f, sign] :
           {std::tuple{n_ + i, &dry, 1.0}, std::tuple{sVap_, &dry, -1.0}, std::tuple{sQ_, &q, -1.0}}) {
        sink.add(row, col_m(i), sign * f->v[0]);
        sink.add(row, col_w(i), sign * f->v[1]);
        for (int d = 2; d < 7; ++d) sink.add(row, cols[d], sign * f->v[d]);
      }
      ddry_dratio[i] = dry.v[7];
      dvap_dratio -= dry.v[7];
      dq_dratio -= q.v[7];
    }
    for (int j = 0; j < n_; ++j) {
      const double r = surface_per_mass_[j] / c.par(kABed);  // d ratio / d M_j
      for (int i = 0; i < n_; ++i) sink.add(n_ + i, col_m(j), ddry_dratio[i] * r);
      sink.add(sVap_, col_m(j), dvap_dratio * r);
      sink.add(sQ_, col_m(j), dq_dratio * r);
    }
    sink.add(sVap_, c.offset + sVap_, 1.0);
    sink.add(sQ_, c.offset + sQ_, 1.0);
    // u0 row: u0 - V/A with V from the inlet's dry-gas flow at inlet conditions
    sink.add(sU0_, c.offset + sU0_, 1.0);
    {
      const J4 m(c.port(kInletProbe, gas::kMdot), 0), t(c.port(kInletProbe, gas::kT), 1),
          y(c.port(kInletProbe, gas::kY), 2), p(c.port(kInletProbe, gas::kP), 3);
      const J4 u = tr::superficial_velocity(J4(m / props::dry_air_partial_density(t, p, y)), J4(c.par(kABed)));
      const int in_cols[4] = {ports[kInletProbe][gas::kMdot], ports[kInletProbe][gas::kT], ports[kInletProbe][gas::kY],
                              ports[kInletProbe][gas::kP]};
      for (int k = 0; k < 4; ++k) sink.add(sU0_, in_cols[k], -u.v[k]);
    }
    // deposition into the W rows and the enthalpy row (Eq. (59)); enthalpy row's other terms
    const double t_s = c.x_(sT_);
    if (c.connected(kWet)) {
      const double t_liq = c.port(kWet, wetting::T(n_));
      double h_dep = 0;
      for (int i = 0; i < n_; ++i) {
        const int col = ports[kWet][wetting::mdot(i)];
        h_dep += c.port(kWet, wetting::mdot(i));
        sink.add(n_ + i, col, -1.0);
        sink.add(sH_, col, -props::liquid_water_enthalpy(t_liq, c.par(kCpL)));
      }
      sink.add(sH_, ports[kWet][wetting::T(n_)], -h_dep * c.par(kCpL));
    }
    sink.add(sH_, c.offset + sVap_, props::vapour_enthalpy(t_s));
    sink.add(sH_, col_ts, c.x_(sVap_) * props::kCpVapour);
    sink.add(sH_, c.offset + sQ_, -1.0);
    // T row: H - C (T_S - T0), Eq. (60)
    double heat_capacity = 0;
    sink.add(sT_, c.offset + sH_, 1.0);
    for (int i = 0; i < n_; ++i) {
      heat_capacity += c.x_(i) * c.par(kCpS) + c.x_(n_ + i) * c.par(kCpL);
      sink.add(sT_, col_m(i), -c.par(kCpS) * (t_s - props::kT0));
      sink.add(sT_, col_w(i), -c.par(kCpL) * (t_s - props::kT0));
    }
    sink.add(sT_, col_ts, -heat_capacity);
    return true;
  }

  void report(const Ctx<double>& c, double* out) const override {
    double m = 0, w = 0, n = 0;
    std::vector<double> mass(n_);
    for (int i = 0; i < n_; ++i) {
      mass[i] = c.x_(i);
      m += c.x_(i);
      w += c.x_(n_ + i);
      n += c.x_(i) / particle_mass_[i];
    }
    const double q[] = {0.1, 0.5, 0.9, 0.05, 0.16, 0.25, 0.75, 0.84, 0.95};  // order of o_quantiles_
    for (size_t k = 0; k < o_quantiles_.size(); ++k)
      out[o_quantiles_[k]] = kernels::characteristic_diameter_of_mass(grid_->diameter_edges(), mass.data(), q[k]);
    out[o_moisture_] = w / m;
    out[o_moisture_wet_] = w / (m + w);
    out[o_particles_] = n;
    out[o_top_] = mass[n_ - 1] / m;
    std::vector<double> dry(n_);
    double qv = 0;
    int reg_eta = 0, reg_a = 0;
    transfer(c, tables(c.p), dry.data(), &qv, &reg_eta, &reg_a);
    out[o_reg_eta_] = reg_eta;
    out[o_reg_a_] = reg_a;
    out[o_balance_] = w;
    out[o_balance_ + 1] = m;
    out[o_balance_ + 2] = c.x_(sH_);
    for (int i = 0; i < n_; ++i) {
      out[o_psd_ + i] = grid_->diameter_pivots()[i];
      out[o_psd_ + n_ + i] = mass[i];
    }
  }

 private:
  // Per scalar type work arrays of the residual, sized once in declare() (the unit is evaluated by one solver
  // at a time, as pbm_batch's).
  template <class T>
  struct Scratch {
    std::vector<T> dM, dW, X, dry, number, fwet, sticky, pm, spm, shape, frag;
    void resize(int n) {
      for (auto* v : {&dM, &dW, &X, &dry, &number, &fwet, &sticky, &pm, &spm, &shape}) v->assign(n, T(0.0));
      frag.assign(size_t(n) * n, T(0.0));
    }
  };
  template <class T>
  Scratch<T>& scratch() const {
    if constexpr (std::is_same_v<T, double>)
      return sd_;
    else
      return sj_;
  }

  struct Pair {
    int j, k, a;
    double frac_upper;  // mass fraction of the aggregate landing on pivot a + 1
    bool beyond;        // the aggregate is beyond the top pivot (kept in the top class)
  };

  // Moisture of class i, kg/kg dry; the floor keeps an emptied class finite.
  template <class T>
  T moisture(const Ctx<T>& c, int i) const {
    return c.x_(n_ + i) / (c.x_(i) + kMassFloor);
  }

  // Superficial velocity from the inlet flow at inlet conditions, Eq. (77), paper 001.
  template <class T>
  T inlet_velocity(const Ctx<T>& c) const {
    const T rho_da = props::dry_air_partial_density(c.port(kInletProbe, gas::kT), c.port(kInletProbe, gas::kP),
                                                    c.port(kInletProbe, gas::kY));
    return tr::superficial_velocity(T(c.port(kInletProbe, gas::kMdot) / rho_da), c.par(kABed));
  }

  // Eqs. (21)-(24) with the kernel of Eq. (39) (or a constant one) on the mass-based fixed pivot; water moves
  // with the solid mass: an agglomerate carries the mass-weighted loading of its partners.
  template <class T>
  void aggregation(const Ctx<T>& c, const T* X, const T* pm, T* dM, T* dW, T* beyond) const {
    // Without a wetting port no surface is wet: psi_geom = 0 (Eq. (40)) makes every glass-transition beta 0.
    if (agg_ == Aggregation::kGlassTransition && !c.connected(kWet)) return;
    const auto& d = grid_->diameter_pivots();
    Scratch<T>& w = scratch<T>();
    T* number = w.number.data();
    T* fwet = w.fwet.data();
    T* sticky = w.sticky.data();
    for (int i = 0; i < n_; ++i) {
      number[i] = c.x_(i) / pm[i];
      if (agg_ == Aggregation::kGlassTransition) {
        fwet[i] = c.port(kWet, wetting::fwet(n_, i));
        const T& xwet = c.port(kWet, wetting::Xwet(n_, i));
        const T tg = p1::gordon_taylor(xwet, c.par(kGtK), c.par(kTgL), c.par(kTgS));                   // Eq. (54)
        sticky[i] = p1::sticky_probability(c.x_(sT_), tg, c.par(kStickySlope), c.par(kStickyOffset));  // Eq. (53)
      }
    }
    const T scale = per_volume_ ? T(1.0 / c.par(kVVessel)) : T(1.0);
    T beta_constant(0.0);
    if (agg_ == Aggregation::kConstant) {
      using std::exp;
      beta_constant = exp(c.par(kLnBeta0));
    }
    for (size_t q = 0; q < pairs_.size(); ++q) {
      const Pair& pr = pairs_[q];
      const int j = pr.j, k = pr.k;
      T beta;
      if (agg_ == Aggregation::kGlassTransition) {
        T cf;  // Eq. (37); Jets recompute it so that sensitivities to ln_beta0 and tau_spray carry through
        if constexpr (std::is_same_v<T, double>)
          cf = cf_[q];
        else
          cf = p1::collision_frequency(T(d[j]), T(d[k]), c.par(kLnBeta0), c.par(kTauSpray));
        beta = p1::agglomeration_kernel(cf, p1::geometric_success_factor(fwet[j], fwet[k]),
                                        p1::physical_success_factor(sticky[j], sticky[k]));  // Eq. (39)
      } else {
        beta = beta_constant;
      }
      // events per second: 1/2 beta N_j^2 for like pairs, beta N_j N_k otherwise (Eq. (21) and (24))
      const T events = (j == k ? 0.5 : 1.0) * scale * beta * number[j] * number[k];
      const T mj = events * pm[j], mk = events * pm[k];
      const T m_agg = mj + mk, w_agg = mj * X[j] + mk * X[k];
      dM[j] -= mj;
      dM[k] -= mk;
      dW[j] -= mj * X[j];
      dW[k] -= mk * X[k];
      const double up = pr.frac_upper;
      dM[pr.a] += (1.0 - up) * m_agg;
      dW[pr.a] += (1.0 - up) * w_agg;
      if (up > 0) {
        dM[pr.a + 1] += up * m_agg;
        dW[pr.a + 1] += up * w_agg;
      }
      if (pr.beyond) *beyond += m_agg;
    }
  }

  // Gas-side quantities shared by all classes' drying and heat transfer.
  template <class T>
  struct GasSide {
    T t_s, t_g, y, u0, ratio, rho_da, nu, sc, pr, x_eq, y_sat;
    bool activity_capped, saturation_capped;
  };
  template <class T>
  GasSide<T> gas_side(const T& t_s, const T& t_g, const T& y, const T& p, const T& u0, const T& ratio,
                      const T* par) const {
    GasSide<T> g{t_s, t_g, y, u0, ratio, T(0.0), T(0.0), T(0.0), T(0.0), T(0.0), T(0.0), false, false};
    const T rho = props::humid_air_density(t_g, p, y);
    g.rho_da = props::dry_air_partial_density(t_g, p, y);  // Y is per kg dry air in Eq. (72)
    const T mu = props::air_viscosity(t_g);
    g.nu = props::kinematic_viscosity(mu, rho);
    g.sc = props::schmidt_number(mu, rho, par[kDv]);                                // Eq. (78)
    g.pr = props::prandtl_number(props::humid_heat_capacity(y), mu, par[kLambda]);  // Eq. (89)
    // Eqs. (82)-(83): activity of the bulk gas at the solids temperature; BET (81) is singular at a = 1
    const auto a = kernels::cap_at(p1::water_activity(y, t_s, p), T(0.99));
    g.activity_capped = a.active;
    g.x_eq = p1::bet_equilibrium_moisture(a.value, par[kBetMm], par[kBetN]);  // Eq. (81)
    const auto ys = p1::saturation_humidity(t_s, p);  // Y_eq at T_S (docs/paper001_decisions.md), capped near boiling
    g.y_sat = ys.value;
    g.saturation_capped = ys.active;
    return g;
  }

  // Drying rate (Eqs. (70)-(80)) and gas-to-solid heat flow (Eqs. (85)-(89)) of class i; returns whether the
  // Eq. (80) regularization replaced the literal equation.
  template <class T>
  bool class_transfer(int i, const T& m, const T& w, const T& particle_mass, const GasSide<T>& g, const T* par, T* dry,
                      T* q) const {
    const T di(grid_->diameter_pivots()[i]);
    const T area = kernels::class_surface(T(m / particle_mass), di);  // N_i pi d_i^2 (docs/paper001_decisions.md)
    const T re0 = tr::particle_reynolds_number(g.u0, di, g.nu);       // Eq. (76)
    const T shb = tr::bulk_sherwood(tr::sherwood_single(re0, g.sc), re0, g.sc, g.ratio, par[kShCorr]);  // (74), (75)
    const T j =
        p1::drying_mass_flux(g.rho_da, tr::mass_transfer_coefficient(shb, par[kDv], di), g.y_sat, g.y);  // (72), (73)
    const auto eta = p1::normalized_moisture(T(w / (m + kMassFloor)), g.x_eq, par[kXcr]);  // Eq. (80), regularized
    *dry = p1::drying_rate(p1::linear_drying_curve(eta.value), area, j);                   // Eqs. (70), (79)
    const T nub = tr::bulk_nusselt(tr::nusselt_single(re0, g.pr), re0, g.pr, g.ratio);     // Eqs. (87), (88)
    *q = tr::heat_transfer_coefficient(nub, par[kLambda], di) * area * (g.t_g - g.t_s);    // Eqs. (85), (86)
    return eta.active;
  }

  // A_p / A_inlet of Eqs. (74), (87): total particle surface of the bed over the cross-section; its derivative
  // with respect to M_i is the constant surface per mass spm[i] / A_bed.
  template <class T>
  T area_ratio(const Ctx<T>& c, const T* spm) const {
    T surface(0.0);
    for (int i = 0; i < n_; ++i) surface += c.x_(i) * spm[i];
    return tr::bed_area_ratio(surface, c.par(kABed));
  }

  // Drying and heat transfer of every class; counts the regularizations that replaced the literal equations.
  template <class T>
  void transfer(const Ctx<T>& c, const Tables<T>& tb, T* dry, T* q, int* reg_eta, int* reg_a) const {
    const GasSide<T> g = gas_side(c.x_(sT_), c.port(kGasProbe, gas::kT), c.port(kGasProbe, gas::kY),
                                  c.port(kGasProbe, gas::kP), c.x_(sU0_), area_ratio(c, tb.spm), c.p);
    *reg_a += g.activity_capped + g.saturation_capped;
    *q = T(0.0);
    for (int i = 0; i < n_; ++i) {
      T qi;
      *reg_eta += class_transfer(i, c.x_(i), c.x_(n_ + i), tb.pm[i], g, c.p, &dry[i], &qi);
      *q += qi;
    }
  }

  int n_ = def::kSizeClasses;
  static constexpr double kMassFloor = holdup::kMassFloor;
  int sH_ = 0, sT_ = 0, sU0_ = 0, sVap_ = 0, sQ_ = 0, sTop_ = 0;
  std::vector<int> o_quantiles_;  // output indices
  int o_moisture_ = 0, o_moisture_wet_ = 0, o_particles_ = 0, o_top_ = 0, o_reg_eta_ = 0, o_reg_a_ = 0, o_balance_ = 0,
      o_psd_ = 0;
  Aggregation agg_ = Aggregation::kGlassTransition;
  bool breakage_ = true, per_volume_ = false;
  p1::BreakageSizeUnit size_unit_ = p1::BreakageSizeUnit::kMicrometre;
  std::unique_ptr<kernels::Grid> grid_;
  std::vector<Pair> pairs_;
  std::vector<double> shape_, frag_, particle_mass_, surface_per_mass_, cf_;
  mutable Scratch<double> sd_;
  mutable Scratch<Jet> sj_;
};

}  // namespace

void register_fluid_bed(Registry<Unit>& r) {
  r.add("fluid_bed", "batch fluid bed: population balance, drying and heat transfer (paper 001)",
        [] { return std::make_unique<FluidBed>(); });
}

}  // namespace granuflow::units
