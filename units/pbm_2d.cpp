// Batch population balance over solid and liquid volume (paper 002, Eqs. (6)-(10)):
//     dN_ij/dt = aggregation_ij(N) + deposition_ij(N) + drying_ij(N)
// on bins (s_i, l_j): the particle system's solid grid times a uniform liquid grid (kernels/discretization/grid2d.hpp
// says why the liquid coordinate is a volume). Aggregation by any registered kernel through the 2-D engine
// (kernels/population/population2d.hpp), conserving number, solid and liquid volume; in the paper's case the DEM kernel
// (dem_collision: collision frequencies from a DEM count file, Eq. (12), times the liquid-content efficiency, Eq.
// (13)).
//
// Liquid addition (units/pbm_2d_spray.hpp): droplets absorbed whole (paper 002, section 3.2) or a continuous flow
// over the particles (Eq. (6)), shared per particle, by surface or by cross-section (setting spray_weight). A bin's
// particles leave at rate R w_a / W towards l_j + v_d, split between the two liquid pivots around it so that number
// and liquid volume are kept; the liquid added is exactly Q. W = sum_b w_b N_b + w_out N_out counts the particles that
// left the grid too (still in the vessel, they meet the spray): without them the last particles on the grid would take
// all the liquid however few they are, a drain that does not vanish with them.
//
// Drying (setting drying: surface): the constant-rate period of a wet particle, liquid volume lost at j_dry pi D^2 per
// particle (surface-proportional evaporation, paper 000, section 2.2), moved down the liquid axis by first-order upwind
// fluxes, which remove exactly the evaporated volume.
//
// What leaves the grid (aggregates beyond the solid grid, liquid beyond the liquid axis) is integrated in book-keeping
// states (number, solid and liquid volume), so solid and liquid balances close to round-off and are reported; the top
// class of Eq. (14) holds that mass (as the 1-D top class holds what grew beyond its grid), so the grid-end warnings
// cover it. Bin numbers are inventories declared non-negative (the integrators enforce it).
//
// Linear algebra: below dense_limit states the analytic Jacobian (complete) with dense LU; above it GMRES with the
// unit's preconditioner: per solid class the exact block of the liquid-axis couplings (deposition, drying) and the
// death rates of aggregation on its diagonal (docs/pbm_2d.md measures both).
#include "pbm_2d.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/aggregation/dem_collision.hpp"
#include "kernels/discretization/initial_distribution.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/population/population2d.hpp"
#include "particles.hpp"
#include "pbm_2d_spray.hpp"

namespace granuflow::units {
namespace {

using namespace kernels;
constexpr double kPi = 3.14159265358979323846;

enum class Initial { kMono, kExponential };
using pbm2d::Spray;
using pbm2d::SprayWeight;

// Rows of the unit's outside rates: the engine's (number, solid, liquid that left the grid), then evaporated liquid.
constexpr int kEvaporated = kOut2Rows, kRateRows = kOut2Rows + 1;

struct Work : Workspace {
  Population2D::WorkPtr pop;
  std::vector<double> dN, out, death;
  std::vector<Jet> dNj, outj;
  template <class T>
  std::vector<T>& rates() {
    if constexpr (std::is_same_v<T, double>)
      return dN;
    else
      return dNj;
  }
  template <class T>
  std::vector<T>& outside() {
    if constexpr (std::is_same_v<T, double>)
      return out;
    else
      return outj;
  }
  double solid0 = 0.0, liquid0 = 0.0;  // on-grid volumes at t = 0, m^3
  // preconditioner: one LU per solid class over its liquid axis
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXd>> lu;
  Eigen::MatrixXd block;
  // analytic Jacobian: local rows of the bins and outside rows, global columns of the bins
  std::vector<int> rows, cols;
};

class Pbm2D : public UnitBase<Pbm2D> {
 public:
  std::string type() const override { return "pbm_2d"; }

  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st);
    require_water(ps, st, "the 2-D population holds liquid on the particles");
    pp_ = ps.params();
    const auto solid = ps.grid();
    const long nl = st.get_int("liquid_classes", 20, 2, 4000, "liquid classes (pivots l_j = j dl from 0)");
    const double l_max =
        st.get_real("liquid_max", solid->pivot(solid->size() - 1), 1e-30, 1e6,
                    "liquid volume the liquid axis spans, m3: dl = liquid_max / liquid_classes (default: the top "
                    "solid pivot)");
    grid_ = std::make_shared<const Grid2D>(solid, static_cast<int>(nl), l_max / double(nl));
    ns_ = grid_->ns(), nl_ = grid_->nl(), n_ = grid_->size();
    const double number_scale = st.get_real(
        "number_scale", 1.0, 1e-30, 1e30, "typical particle number per bin; absolute tolerance = atol * number_scale");
    initial_ =
        st.get_choice("initial", "mono", {"mono", "exponential"},
                      "initial solid distribution: one size d0, or exponential in volume (verification)") == "mono"
            ? Initial::kMono
            : Initial::kExponential;
    p_n0_ = s.add_param({"N0", "-", 1.0, 0.0, 1e30,
                         "initial particle number (with a DEM collision file: at most its DEM population)",
                         "initial state (user); bound: docs/pbm_2d.md"});
    if (initial_ == Initial::kMono)
      p_size0_ = s.add_param({"d0", "m", 2e-3, 1e-9, 1.0, "initial particle diameter (solid volume)",
                              "paper 002, section 3.2: 2 mm primary particles"});
    else
      p_size0_ = s.add_param({"v0", "m3", 1.0, 1e-30, 1e6, "initial mean solid volume", "docs/verification.md"});
    p_lc0_ = s.add_param({"lc0", "-", 0.0, 0.0, 0.95, "initial liquid content l / (s + l) of every particle",
                          "initial state (user); paper 002 starts dry"});
    p_rho_l_ = s.add_param(
        {"rho_l", "kg/m3", 1000.0, 100.0, 5000.0, "liquid density (masses of Eq. (14))", "binder as water (user)"});
    declare_mechanisms(s, st);
    Population2DOptions o;
    pop_.declare(s, st, grid_, o);
    declare_psd_classes(st, *solid, l_max);
    declare_states(s, *solid, number_scale);
    declare_outputs(s);
  }

 private:
  // Spray and drying: their settings and parameters.
  void declare_mechanisms(UnitSpec& s, Settings& st) {
    const std::string spray = st.get_choice(
        "spray", "none", {"none", "droplets", "continuous"},
        "liquid addition: none; droplets absorbed whole by one particle each (paper 002, section 3.2); or continuous, "
        "a flow of liquid over the particles (paper 002, Eq. (6))");
    spray_ = spray == "none" ? Spray::kNone : spray == "droplets" ? Spray::kDroplets : Spray::kContinuous;
    const std::string weight =
        st.get_choice("spray_weight", "number", {"number", "surface", "cross_section"},
                      "how the sprayed liquid is shared: per particle alike, in proportion to the surface D^2, or "
                      "(droplets only) to the cross-section (D + d_drop)^2 of a droplet meeting the particle");
    weight_ = weight == "number"    ? SprayWeight::kNumber
              : weight == "surface" ? SprayWeight::kSurface
                                    : SprayWeight::kCrossSection;
    if (spray_ == Spray::kContinuous && weight_ == SprayWeight::kCrossSection)
      throw ConfigError(st.where() +
                        ".spray_weight = 'cross_section': needs spray: droplets (a continuous flow has no droplet "
                        "size); allowed with spray: continuous: number, surface");
    if (spray_ != Spray::kNone) {
      p_q_ = s.add_param({"spray_rate", "m3/s", 1e-6, 0.0, 1.0, "liquid volume sprayed per second",
                          "operating input; paper 002: 50 000 droplets/s of 2 mm"});
      if (spray_ == Spray::kDroplets)
        p_dd_ = s.add_param({"d_drop", "m", 2e-3, 1e-7, 0.1, "droplet diameter",
                             "paper 002, section 3.2: droplets as large as the particles"});
      p_on_ = s.add_param({"t_spray_on", "s", 0.0, 0.0, 1e7, "spray start", "paper 002: liquid from 0.2 s"});
      p_off_ = s.add_param({"t_spray_off", "s", 1e7, 0.0, 1e7, "spray stop", "operating input"});
    }
    drying_ = st.get_choice("drying", "none", {"none", "surface"},
                            "drying: none, or constant-rate evaporation from the particle surface") == "surface";
    if (drying_)
      p_dry_ = s.add_param({"dry_flux", "m/s", 1e-7, 0.0, 1.0,
                            "liquid volume evaporated per surface area and time (constant-rate period)",
                            "paper 000, section 2.2 (constant-rate drying); value: user"});
  }

  // The size classes of Eq. (14) and the class of each bin.
  void declare_psd_classes(Settings& st, const kernels::Grid& solid, double l_max) {
    const long npsd = st.get_int("psd_classes", 20, 2, 1000, "size classes of Eq. (14), log-spaced in diameter");
    const double dmin = st.get_real("psd_d_min", solid.diameter_edges().front(), 1e-9, 1.0,
                                    "lowest edge of the size classes of Eq. (14), m");
    const double dmax =
        st.get_real("psd_d_max", diameter_of_volume(solid.edges().back() + l_max), 1e-9, 1.0,
                    "highest edge of the size classes of Eq. (14), m (default: top solid edge plus liquid_max)");
    if (!(dmax > dmin))
      throw ConfigError(
          violation(st.where() + ".psd_d_max", dmax, "m", "psd_d_max > psd_d_min (" + fmt_num(dmin) + ")"));
    psd_edges_.resize(npsd + 1);
    for (long k = 0; k <= npsd; ++k) psd_edges_[k] = dmin * std::pow(dmax / dmin, double(k) / npsd);
    // Eq. (14)'s D_ij: the particle's (Eq. (15) uses s + l), or the DEM particle's, whose liquid is implicit
    const bool solid_only =
        st.get_choice("psd_diameter", "total", {"total", "solid"},
                      "the diameter that puts a bin in a size class of Eq. (14): of solid plus liquid volume, or of "
                      "the solid volume alone (the DEM particle's size in paper 002)") == "solid";
    psd_class_.resize(n_);
    for (int a = 0; a < n_; ++a) {
      const double d = solid_only ? diameter_of_volume(grid_->solid_volume(a)) : grid_->diameter(a);
      int k = static_cast<int>(std::upper_bound(psd_edges_.begin(), psd_edges_.end(), d) - psd_edges_.begin()) - 1;
      psd_class_[a] = std::clamp(k, 0, static_cast<int>(npsd) - 1);  // Eq. (14): end classes take the tails
    }
  }

  void declare_states(UnitSpec& s, const kernels::Grid& solid, double number_scale) {
    for (int i = 0; i < ns_; ++i)
      for (int j = 0; j < nl_; ++j) {
        const StateId id =
            s.add_state("N_" + std::to_string(i) + "_" + std::to_string(j), StateKind::Differential, "-", number_scale);
        if (i == 0 && j == 0) sN_ = id;
      }
    const double s_mid = solid.pivot(ns_ / 2), l_mid = grid_->liquid(nl_ / 2 + 1);
    if (pop_.aggregation() || spray_ != Spray::kNone) {
      s_out_[kOut2Number] = s.add_accumulator("number_left", "-", number_scale);
      s_out_[kOut2Solid] = s.add_accumulator("solid_left", "m3", number_scale * s_mid);
      s_out_[kOut2Liquid] = s.add_accumulator("liquid_left", "m3", number_scale * l_mid);
    }
    if (drying_) s_out_[kEvaporated] = s.add_accumulator("liquid_evaporated", "m3", number_scale * l_mid);
    n_states_ = static_cast<int>(s.states().size());
    s.set_nonnegative(sN_, n_);
    for (const StateId& o : s_out_)
      if (o) s.set_nonnegative(o);
    s.set_analytic_part(true);
    s.set_preconditioner();
  }

  void declare_outputs(UnitSpec& s) {
    if (spray_ != Spray::kNone)
      q_sprayed_ = s.add_quadrature("liquid_sprayed", "kg", 1e-3, OutputRole::kBalanceIn, "water");
    o_number_ = s.add_output("number", "-");
    o_davg_ = s.add_output("D_avg", "m");
    o_xavg_ = s.add_output("x_avg", "-");
    o_d50_ = s.add_output("d50", "m");
    o_vs_ = s.add_output("solid_volume", "m3");
    o_vl_ = s.add_output("liquid_volume", "m3");
    o_ms_ = s.add_output("solids_mass", "kg", OutputRole::kBalanceHold, "solids");
    o_ml_ = s.add_output("liquid_mass", "kg", OutputRole::kBalanceHold, "water");
    o_msl_ = s.add_output("solids_left_grid", "kg", OutputRole::kBalanceOut, "solids");
    o_mll_ = s.add_output("liquid_left_grid", "kg", OutputRole::kBalanceOut, "water");
    if (drying_) o_mev_ = s.add_output("liquid_evaporated_mass", "kg", OutputRole::kBalanceOut, "water");
    o_sbal_ = s.add_output("solid_balance", "-");
    o_lbal_ = s.add_output("liquid_balance", "-");
    o_end_ = s.add_output("grid_end_mass_fraction", "-", OutputRole::kGridEnd);
    for (int k = 0; k + 1 < static_cast<int>(psd_edges_.size()); ++k) {
      const OutputId d = s.add_output("psd_d_" + std::to_string(k), "m", OutputRole::kSizeDiameter, "", k);
      s.add_output("psd_mass_" + std::to_string(k), "kg", OutputRole::kSizeMass, "", k);
      s.add_output("mu_" + std::to_string(k), "-");
      if (k == 0) o_psd_ = d;
    }
    for (int i = 0; i < ns_; ++i) {
      const OutputId o = s.add_output("solid_pivot_" + std::to_string(i), "m3");
      if (i == 0) o_spiv_ = o;
    }
    for (int j = 0; j < nl_; ++j) {
      const OutputId o = s.add_output("liquid_pivot_" + std::to_string(j), "m3");
      if (j == 0) o_lpiv_ = o;
    }
  }

 public:
  std::unique_ptr<Workspace> workspace() const override {
    auto w = std::make_unique<Work>();
    w->pop = pop_.make_work();
    return w;
  }

  void check(const UnitSpec&, const double* p) const override {
    if (spray_ != Spray::kNone && p[p_off_.i] < p[p_on_.i])
      throw ConfigError(
          violation("t_spray_off", p[p_off_.i], "s", "t_spray_off >= t_spray_on (" + fmt_num(p[p_on_.i]) + " s)"));
    if (initial_ == Initial::kMono) {
      const double s0 = volume_of_diameter(p[p_size0_.i]);
      const Grid& g = grid_->solid();
      constexpr double kRoundOff = 1e-9;  // a diameter given to print precision may land just off a pivot
      if (!(s0 >= g.pivot(0) * (1 - kRoundOff) && s0 <= g.pivot(ns_ - 1) * (1 + kRoundOff)))
        throw ConfigError(violation("d0", p[p_size0_.i], "m",
                                    "the solid grid's pivots (" + fmt_num(g.diameter_pivots().front()) + " to " +
                                        fmt_num(g.diameter_pivots().back()) + " m)"));
    }
    check_population(p[p_n0_.i]);
    // the initial liquid l = s lc0 / (1 - lc0) of the largest particles present must fit on the liquid axis
    const double lc = p[p_lc0_.i];
    const double s_top = initial_ == Initial::kMono ? volume_of_diameter(p[p_size0_.i]) : grid_->solid().pivot(ns_ - 1);
    if (s_top * lc / (1.0 - lc) > grid_->liquid(nl_ - 1))
      throw ConfigError(violation("lc0", lc, "",
                                  "initial liquid volume s lc0 / (1 - lc0) <= the top liquid pivot (" +
                                      fmt_num(grid_->liquid(nl_ - 1)) + " m3; setting liquid_max)"));
  }

  // Eq. (12)'s frequencies are per pair of particles at the DEM run's population (sum F_i, in its vessel): the same
  // vessel holding more particles is a denser bed than the one measured, whose particles collide more often than the
  // counts say (and N0 far beyond it only makes the run grind through aggregation times of 1e-25 s). Fewer particles
  // are a dilute bed, where a pair's frequency changes little.
  void check_population(double n0) const {
    const auto* dem = dynamic_cast<const kernels::DemCollisionKernel*>(pop_.kernel());
    if (!dem || !dem->counts()) return;
    const kernels::CollisionCounts& f = *dem->counts();
    double total = 0.0;
    for (double x : f.particles) total += x;
    if (n0 > total)
      throw ConfigError(violation("N0", n0, "",
                                  "N0 <= " + fmt_num(total) + ", the DEM population of " + f.path +
                                      " (its per-pair frequencies, Eq. (12), hold at that population)"));
  }

  void configure(const UnitSpec& spec, const double* p, const double* shared, Workspace& ws) const override {
    Work& w = static_cast<Work&>(ws);
    pop_.configure(*w.pop, p, "unit pbm_2d");
    std::vector<double> x0(spec.states().size());
    InitCtx<double> ic{p, x0.data(), shared, &ws};
    init(ic);
    w.solid0 = w.liquid0 = 0.0;
    for (int a = 0; a < n_; ++a)
      w.solid0 += x0[sN_.i + a] * grid_->solid_volume(a), w.liquid0 += x0[sN_.i + a] * grid_->liquid_volume(a);
    w.rows.clear();
  }

  std::vector<double> breakpoints(const double* p) const override {
    if (spray_ == Spray::kNone) return {};
    return {p[p_on_.i], p[p_off_.i]};
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    Work& w = c.template ws<Work>();
    auto& dN = w.template rates<T>();
    auto& out = w.template outside<T>();
    rates(c, w, dN, out);
    for (int a = 0; a < n_; ++a) c.res(sN_ + a) = c.xd(sN_ + a) - dN[a];
    for (int k = 0; k < kRateRows; ++k)
      if (s_out_[k]) c.res(s_out_[k]) = c.xd(s_out_[k]) - out[k];
    return Status::kOk;
  }

  // The liquid the particles absorb: all that is sprayed while there are particles to meet (deposition sums to Q
  // whenever the weights' total W > 0), none once the population has left the grid.
  template <class T>
  void quad(const Ctx<T>& c) const {
    if (!q_sprayed_) return;
    c.r[q_sprayed_.i] = T(0.0);
    if (spraying(c) && value_of(deposit_terms(c, &c.x(sN_)).W) > 0) c.r[q_sprayed_.i] = c.par(p_rho_l_) * c.par(p_q_);
  }

  template <class T>
  void init(InitCtx<T>& c) const {
    for (int a = 0; a < n_; ++a) c.x(sN_ + a) = T(0.0);
    for (int k = 0; k < kRateRows; ++k)
      if (s_out_[k]) c.x(s_out_[k]) = T(0.0);
    const Grid& g = grid_->solid();
    std::vector<T> Ns(ns_, T(0.0));
    if (initial_ == Initial::kMono) {
      const T d0 = c.par(p_size0_);
      const T s0 = kPi / 6.0 * d0 * d0 * d0;
      int a = g.interval_of(value_of(s0));
      if (a < 0) a = 0;
      if (a >= ns_ - 1) {
        Ns[ns_ - 1] = c.par(p_n0_);
      } else {  // split on the two pivots around s0, number and solid volume kept
        T nu = (s0 - g.pivot(a)) / (g.pivot(a + 1) - g.pivot(a));
        if (value_of(nu) < 0) nu = T(0.0);  // within round-off below the first pivot (check())
        Ns[a] = c.par(p_n0_) * (1.0 - nu);
        Ns[a + 1] = c.par(p_n0_) * nu;
      }
    } else {
      std::vector<T> number(ns_), volume(ns_);
      exponential_cells(g, c.par(p_n0_), c.par(p_size0_), number.data(), volume.data());
      bin_cells(g, Binning::kMoments, number.data(), volume.data(), Ns.data());
    }
    // every particle at liquid content lc0: l = s lc0 / (1 - lc0), split on the liquid pivots, number and liquid kept
    const T lc = c.par(p_lc0_);
    for (int i = 0; i < ns_; ++i) {
      const T x = g.pivot(i) * lc / (1.0 - lc) / grid_->liquid_step();
      const int lo = std::min(static_cast<int>(std::floor(value_of(x))), nl_ - 1);
      const T nu = lo + 1 < nl_ ? T(x - double(lo)) : T(0.0);
      c.x(sN_ + grid_->bin(i, lo)) += Ns[i] * (1.0 - nu);
      if (lo + 1 < nl_) c.x(sN_ + grid_->bin(i, lo + 1)) += Ns[i] * nu;
    }
  }

  template <class T>
  void outputs(const Ctx<T>& c) const {
    const Work& w = c.template ws<Work>();
    const T* N = &c.x(sN_);
    const T rho_s = pp_.envelope_density(c.shared), rho_l = c.par(p_rho_l_);
    T number(0.0), dsum(0.0), xsum(0.0), vs(0.0), vl(0.0), end(0.0), mass(0.0);
    const int npsd = static_cast<int>(psd_edges_.size()) - 1;
    std::vector<T> psd(npsd, T(0.0));
    for (int a = 0; a < n_; ++a) {
      const T m = N[a] * (rho_s * grid_->solid_volume(a) + rho_l * grid_->liquid_volume(a));
      number += N[a];
      dsum += N[a] * grid_->diameter(a);        // Eq. (15), paper 002
      xsum += N[a] * grid_->liquid_content(a);  // Eq. (16), paper 002
      vs += N[a] * grid_->solid_volume(a);
      vl += N[a] * grid_->liquid_volume(a);
      psd[psd_class_[a]] += m;
      mass += m;
      if (a / nl_ == ns_ - 1 || a % nl_ == nl_ - 1) end += m;
    }
    auto acc = [&](int k) { return s_out_[k] ? T(c.x(s_out_[k])) : T(0.0); };
    // what left the grid: in the top class (the grid-end warnings then say how much)
    const T left = rho_s * acc(kOut2Solid) + rho_l * acc(kOut2Liquid);
    psd[npsd - 1] += left, mass += left, end += left;
    c.out(o_number_) = number;
    const T none = kernels::undefined_size<T>();  // Eqs. (15)-(16) of an empty grid: undefined (null), not 0
    c.out(o_davg_) = number > 0.0 ? T(dsum / number) : none;
    c.out(o_xavg_) = number > 0.0 ? T(xsum / number) : none;
    c.out(o_d50_) = characteristic_diameter_of_mass(psd_edges_, psd.data(), 0.5);
    c.out(o_vs_) = vs;
    c.out(o_vl_) = vl;
    c.out(o_ms_) = rho_s * vs;
    c.out(o_ml_) = rho_l * vl;
    c.out(o_msl_) = rho_s * acc(kOut2Solid);
    c.out(o_mll_) = rho_l * acc(kOut2Liquid);
    if (drying_) c.out(o_mev_) = rho_l * acc(kEvaporated);
    const T sprayed = q_sprayed_ ? T(c.q(q_sprayed_) / rho_l) : T(0.0);
    c.out(o_sbal_) = w.solid0 > 0 ? T((vs + acc(kOut2Solid) - w.solid0) / w.solid0) : T(0.0);
    const double l_ref = std::max(w.liquid0, value_of(sprayed));
    c.out(o_lbal_) = l_ref > 0 ? T((vl + acc(kOut2Liquid) + acc(kEvaporated) - sprayed - w.liquid0) / l_ref) : T(0.0);
    c.out(o_end_) = mass > 0.0 ? T(end / mass) : T(0.0);
    for (int k = 0; k < npsd; ++k) {
      c.out(o_psd_ + 3 * k) = T(std::sqrt(psd_edges_[k] * psd_edges_[k + 1]));
      c.out(o_psd_ + (3 * k + 1)) = psd[k];
      c.out(o_psd_ + (3 * k + 2)) = mass > 0.0 ? T(psd[k] / mass) : T(0.0);  // Eq. (14), paper 002
    }
    for (int i = 0; i < ns_; ++i) c.out(o_spiv_ + i) = T(grid_->solid().pivot(i));
    for (int j = 0; j < nl_; ++j) c.out(o_lpiv_ + j) = T(grid_->liquid(j));
  }

  // dF/dN + cj dF/dN' of the whole unit: bilinear aggregation, deposition (with its rank-one normalization), drying.
  void analytic_jacobian(const Ctx<double>& c, double cj, JacobianSink& sink) const override {
    Work& w = c.template ws<Work>();
    const double* N = &c.x(sN_);
    if (w.rows.empty()) {
      w.rows.resize(n_ + kRateRows), w.cols.resize(n_);
      for (int a = 0; a < n_; ++a) w.rows[a] = sN_.i + a, w.cols[a] = c.offset + sN_.i + a;
      for (int k = 0; k < kRateRows; ++k) w.rows[n_ + k] = s_out_[k] ? s_out_[k].i : -1;
    }
    for (int a = 0; a < n_; ++a) sink.add(sN_.i + a, c.offset + sN_.i + a, cj);
    for (int k = 0; k < kRateRows; ++k)
      if (s_out_[k]) sink.add(s_out_[k].i, c.offset + s_out_[k].i, cj);
    pop_.aggregation_jacobian(*w.pop, N, c.p, w.rows, w.cols, -1.0, sink);
    if (spraying(c)) {
      pbm2d::Deposit<double> dep = deposit_terms(c, N);
      if (dep.W > 0) {
        // rate_a = R w_a N_a / W: d/dN_a = R w_a / W, and -R w_a N_a w_b / W^2 for every b (one outer product)
        std::vector<double> u(n_states_, 0.0);
        for (int a = 0; a < n_; ++a) {
          const double direct = dep.R * dep.w[a] / dep.W;
          const double shared = -dep.R * dep.w[a] * N[a] / (dep.W * dep.W);
          place_deposit(a, dep, [&](int row, double v) {
            sink.add(row, c.offset + sN_.i + a, -v * direct);
            u[row] += -v * shared;
          });
        }
        std::vector<int> cols(w.cols.begin(), w.cols.end());
        std::vector<double> wts(dep.w.begin(), dep.w.end());
        if (dep.n_out > 0) {  // droplets off the grid: v_d R g / W into the liquid that left, g = w_out N_out
          const int rl = s_out_[kOut2Liquid].i;
          u[rl] += dep.vd * dep.R * dep.w_out * dep.n_out / (dep.W * dep.W);
          for (int q : {kOut2Number, kOut2Solid, kOut2Liquid}) {
            const double g = q == kOut2Number ? dep.g_n : dep.g_v;  // dg/d(that state)
            if (g == 0.0) continue;
            sink.add(rl, c.offset + s_out_[q].i, -dep.vd * dep.R * g / dep.W);
            cols.push_back(c.offset + s_out_[q].i), wts.push_back(g);
          }
        }
        sink.add_outer(static_cast<int>(u.size()), u.data(), static_cast<int>(cols.size()), cols.data(), wts.data());
      }
    }
    if (drying_) {
      const double jd = c.par(p_dry_), dl = grid_->liquid_step();
      for (int a = 0; a < n_; ++a) {
        if (a % nl_ == 0) continue;
        const double u = jd * kPi * grid_->diameter(a) * grid_->diameter(a);
        sink.add(sN_.i + a, c.offset + sN_.i + a, u / dl);
        sink.add(sN_.i + a - 1, c.offset + sN_.i + a, -u / dl);
        sink.add(s_out_[kEvaporated].i, c.offset + sN_.i + a, -u);
      }
    }
  }

  // Per solid class, the liquid-axis block cj I - (deposition + drying + aggregation deaths), factored; the
  // aggregation births (which couple solid classes) are left to GMRES.
  void precondition_setup(const Ctx<double>& c, double cj) const override {
    Work& w = c.template ws<Work>();
    const double* N = &c.x(sN_);
    w.death.assign(n_, 0.0);
    pop_.death_rates(*w.pop, N, c.p, w.death.data());
    pbm2d::Deposit<double> dep;
    const bool spray = spraying(c);
    if (spray) dep = deposit_terms(c, N);
    const double jd = drying_ ? c.par(p_dry_) : 0.0, dl = grid_->liquid_step();
    w.lu.resize(ns_);
    for (int i = 0; i < ns_; ++i) {
      Eigen::MatrixXd& B = w.block;
      B.setZero(nl_, nl_);
      for (int j = 0; j < nl_; ++j) {
        const int a = grid_->bin(i, j);
        B(j, j) += cj + w.death[a];
        if (spray && dep.W > 0) {
          const double rho = dep.R * dep.w[a] / dep.W;
          place_deposit(a, dep, [&](int row, double v) {
            const int r = row - sN_.i;
            if (r >= 0 && r < n_ && r / nl_ == i) B(r % nl_, j) -= v * rho;
          });
        }
        if (drying_ && j > 0) {
          const double u = jd * kPi * grid_->diameter(a) * grid_->diameter(a) / dl;
          B(j, j) += u;
          B(j - 1, j) -= u;
        }
      }
      w.lu[i].compute(B);
    }
  }

  void precondition_solve(const Ctx<double>& c, double cj, const double* r, double* z) const override {
    Work& w = c.template ws<Work>();
    for (int i = 0; i < ns_; ++i)
      Eigen::Map<Eigen::VectorXd>(z + sN_.i + i * nl_, nl_) =
          w.lu[i].solve(Eigen::Map<const Eigen::VectorXd>(r + sN_.i + i * nl_, nl_));
    for (int k = 0; k < kRateRows; ++k)
      if (s_out_[k]) z[s_out_[k].i] = r[s_out_[k].i] / cj;
  }

 private:
  template <class T>
  bool spraying(const Ctx<T>& c) const {
    return spray_ != Spray::kNone && c.t_seg >= value_of(c.par(p_on_)) && c.t_seg < value_of(c.par(p_off_));
  }

  template <class T>
  pbm2d::Deposit<T> deposit_terms(const Ctx<T>& c, const T* N) const {
    const bool out = bool(s_out_[kOut2Number]);
    const T n_out = out ? T(c.x(s_out_[kOut2Number])) : T(0.0);
    const T v_out = out ? T(c.x(s_out_[kOut2Solid]) + c.x(s_out_[kOut2Liquid])) : T(0.0);
    const T dd = spray_ == pbm2d::Spray::kDroplets ? T(c.par(p_dd_)) : T(0.0);
    return pbm2d::deposit_terms(*grid_, spray_, weight_, T(c.par(p_q_)), dd, N, out, n_out, v_out);
  }
  template <class T, class F>
  void place_deposit(int a, const pbm2d::Deposit<T>& d, F&& add) const {
    const int out[kOut2Rows] = {s_out_[kOut2Number].i, s_out_[kOut2Solid].i, s_out_[kOut2Liquid].i};
    pbm2d::place_deposit(*grid_, a, d, sN_.i, out, add);
  }

  template <class T>
  void rates(const Ctx<T>& c, Work& w, std::vector<T>& dN, std::vector<T>& out) const {
    const T* N = &c.x(sN_);
    dN.assign(n_, T(0.0));
    out.assign(kRateRows, T(0.0));
    pop_.aggregation_rates(*w.pop, N, c.p, dN.data(), out.data());
    if (spraying(c)) {
      const pbm2d::Deposit<T> dep = deposit_terms(c, N);
      if (value_of(dep.W) > 0) {
        for (int a = 0; a < n_; ++a) {
          if (value_of(N[a]) == 0.0 && std::is_same_v<T, double>) continue;
          const T rate = dep.R * dep.w[a] * N[a] / dep.W;
          place_deposit(a, dep, [&](int row, const T& v) {
            const int r = row - sN_.i;
            if (r >= 0 && r < n_)
              dN[r] += v * rate;
            else
              for (int k = 0; k < kRateRows; ++k)
                if (s_out_[k].i == row) out[k] += v * rate;
          });
        }
        out[kOut2Liquid] += dep.vd * dep.R * dep.w_out * dep.n_out / dep.W;  // droplets on particles off the grid
      }
    }
    if (drying_) {
      const T jd = c.par(p_dry_);
      const double dl = grid_->liquid_step();
      for (int a = 0; a < n_; ++a) {
        if (a % nl_ == 0) continue;
        const T u = jd * kPi * grid_->diameter(a) * grid_->diameter(a);  // liquid volume per particle and second
        const T flux = N[a] * u / dl;
        dN[a] -= flux;
        dN[a - 1] += flux;
        out[kEvaporated] += N[a] * u;
      }
    }
  }

  ParticleParams pp_;
  std::shared_ptr<const Grid2D> grid_;
  int ns_ = 0, nl_ = 0, n_ = 0, n_states_ = 0;
  Initial initial_ = Initial::kMono;
  Spray spray_ = Spray::kNone;
  bool drying_ = false;
  SprayWeight weight_ = SprayWeight::kNumber;
  Population2D pop_;
  std::vector<double> psd_edges_;
  std::vector<int> psd_class_;
  ParamId p_n0_, p_size0_, p_lc0_, p_rho_l_, p_q_, p_dd_, p_on_, p_off_, p_dry_;
  StateId sN_, s_out_[kRateRows];
  QuadId q_sprayed_;
  OutputId o_number_, o_davg_, o_xavg_, o_d50_, o_vs_, o_vl_, o_ms_, o_ml_, o_msl_, o_mll_, o_mev_, o_sbal_, o_lbal_,
      o_end_, o_psd_, o_spiv_, o_lpiv_;
};

}  // namespace

void register_pbm_2d(Registry<Unit>& r) {
  r.add("pbm_2d",
        "batch population balance over solid x liquid volume: aggregation (DEM kernel), droplet deposition, drying "
        "(paper 002)",
        [] { return std::make_unique<Pbm2D>(); });
}

}  // namespace granuflow::units
