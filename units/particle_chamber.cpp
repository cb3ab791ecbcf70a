#include "particle_chamber.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "chamber_outlet.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/drying/paper001_drying.hpp"
#include "kernels/particle_geometry.hpp"
#include "particle_chamber_work.hpp"

namespace granuflow::units {

using kernels::Field;

namespace {

const char* role_type(ChamberRole r) {
  switch (r) {
    case ChamberRole::kSprayZone:
      return "spray_compartment";
    case ChamberRole::kDryingZone:
      return "drying_compartment";
    default:
      return "granulator";
  }
}

// (u + sqrt(u^2 + eps^2)) / 2: a valve that cannot run backwards, smooth for Newton and the integrator.
template <class T>
T softplus(const T& u, const T& eps) {
  using std::sqrt;
  return 0.5 * (u + sqrt(u * u + eps * eps));
}

constexpr double kValveSmoothing = 1e-3;  // eps = kValveSmoothing M_set / tau_c

}  // namespace

std::string ParticleChamber::type() const { return role_type(role_); }

std::unique_ptr<Workspace> ParticleChamber::workspace() const {
  auto w = std::make_unique<Work>();
  w->pop = pop_.make_work();
  w->sd.resize(n_);
  w->sj.resize(n_);
  w->sd.resize_components(n_, K_ - 1);
  w->sj.resize_components(n_, K_ - 1);
  return w;
}

void ParticleChamber::configure(const UnitSpec&, const double* p, const double* shared, Workspace& ws) const {
  Work& w = static_cast<Work&>(ws);
  w.pm.resize(n_), w.spm.resize(n_), w.floor.resize(n_);
  const double rho = pp_.envelope_density(shared);
  for (int i = 0; i < n_; ++i) {
    w.pm[i] = rho * grid_->pivot(i);
    w.spm[i] = kernels::sphere_surface(grid_->diameter_pivots()[i]) / w.pm[i];
    w.floor[i] = kMassFloor / w.pm[i];  // an emptied class carries a finite moisture
  }
  pop_.configure(*w.pop, p, std::string("unit ") + type());
  w.cls = {};
  w.mapped = false;
}

// The spray lands on the particles' surface (paper 003, Eq. (7.33)); the model has no nucleation from the spray, so
// on an empty bed what is sprayed has nowhere to go and would vanish from the balances (issue 29).
void ParticleChamber::check(const UnitSpec&, const double* p) const {
  closures_.check(p, "drying_curve");
  if (spray_ && p[p_mass_.i] == 0.0 && p[p_spray_.i] > 0.0 && (wet_ || p[p_w_.i] > 0.0))
    throw ConfigError(violation("bed_mass", 0.0, "kg",
                                "bed_mass > 0 while the spray is on (m_spray = " + fmt_num(p[p_spray_.i]) +
                                    " kg/s): the spray layers onto the bed's particles and an empty bed has none; "
                                    "start with particles (bed_mass > 0) or with the spray off"));
}

// Particle masses, surfaces per mass and number floors for this evaluation: cached for doubles; Jets recompute them,
// so that sensitivities to the particle system's density carry through.
namespace {
template <class T, class W, class S>
const T* particle_tables(const Ctx<T>& c, const W& w, S& sc, const ParticleParams& pp, const kernels::Grid& g) {
  const int n = g.size();
  if constexpr (std::is_same_v<T, double>) {
    std::copy(w.spm.begin(), w.spm.end(), sc.spm.begin());
    std::copy(w.pm.begin(), w.pm.end(), sc.pm.begin());
    std::copy(w.floor.begin(), w.floor.end(), sc.floor.begin());
  } else {
    const T rho = pp.envelope_density(c.shared);
    for (int i = 0; i < n; ++i) {
      sc.pm[i] = rho * g.pivot(i);
      sc.spm[i] = kernels::sphere_surface(g.diameter_pivots()[i]) / sc.pm[i];
      sc.floor[i] = kMassFloor / sc.pm[i];
    }
  }
  return sc.pm.data();
}
}  // namespace

template <class T>
T ParticleChamber::spray_solids(const Ctx<T>& c) const {
  return spray_ ? T(c.par(p_spray_) * c.par(p_w_)) : T(0.0);
}

// Without a curve (W - X_eq M) / tau_dry; with one, paper 000, section 5.4.1: the constant rate (X_cr - X_eq) M /
// tau_dry (the first-order rate at X_cr) times v(eta), eta = (X - X_eq) / (X_cr - X_eq) regularized as in paper 001's
// Eq. (80); the linear curve is the first-order rate below X_cr.
template <class T>
T ParticleChamber::drying_rate(const Ctx<T>& c, const T& m, const T& w) const {
  if (!closures_.has_curve()) return (w - c.par(p_xeq_) * m) / c.par(p_taudry_);
  const T &x_eq = c.par(p_xeq_), &x_cr = c.par(p_xcr_);
  T v = kernels::paper001::normalized_moisture(T(w / (m + kMassFloor)), x_eq, x_cr).value;
  v = v < 1.0 ? v : T(1.0);
  closures_.curve(c.p, 1, &v);
  return (x_cr - x_eq) * m / c.par(p_taudry_) * v;
}

template <class T>
void ParticleChamber::inlet_flows(const Ctx<T>& c, T* in_m, T* in_w, std::vector<T>& gather) const {
  std::fill(in_m, in_m + n_, T(0.0));
  std::fill(in_w, in_w + n_, T(0.0));
  for (PortId p : inlets_) {  // inlet by inlet over the classes: plain array loops
    const T* m = c.port_array(p, solids::mdot(0), n_, gather);
    for (int i = 0; i < n_; ++i) in_m[i] += m[i];
    if (!wet_) continue;
    const T* w = c.port_array(p, solids::water(n_, 0), n_, gather);
    for (int i = 0; i < n_; ++i) in_w[i] += w[i];
  }
  if (!composed()) return;
  T* in_q = c.template ws<Work>().template scratch<T>().in_q.data();
  std::fill(in_q, in_q + size_t(n_) * (K_ - 1), T(0.0));
  for (PortId p : inlets_)
    for (int k = 1; k < K_; ++k) {
      const T* q = c.port_array(p, solids::component(n_, k, 0), n_, gather);
      for (int i = 0; i < n_; ++i) in_q[(k - 1) * n_ + i] += q[i];
    }
}

// Paper 003, Eqs. (7.32)-(7.34): the number fluxes F_f through the faces of the cells (fv_growth.hpp), normalized so
// that the created volume is M_sus / rho; in mass, class i gains m_i F_i and loses m_i F_{i+1}; what grows past the
// top face is kept in the top class with its volume (x_hi), so the mass gained is exactly M_sus. Water moves with the
// particles of the donor cell.
template <class T>
void ParticleChamber::growth_rates(const Ctx<T>& c, const T* N, const T* W, const T& amount, T* dM, T* dW) const {
  auto& sc = c.template ws<Work>().template scratch<T>();
  const kernels::GrowthTerms<T> g{1, sc.ones.data(), &amount, true};
  fv_->fluxes(N, g, sc.F.data(), sc.donor.data());
  const T rho = pp_.envelope_density(c.shared);
  const T* pm = sc.pm.data();
  for (int f = 0; f <= n_; ++f) {
    const T& F = sc.F[f];
    if (f > 0) dM[f - 1] -= pm[f - 1] * F;
    if (f < n_)
      dM[f] += pm[f] * F;
    else
      dM[n_ - 1] += rho * grid_->upper_virtual() * F;
    const int d = sc.donor[f];
    if (!W || d < 0 || f == n_) continue;  // water crossing the top face stays in the top class
    const T q = F * W[d] / (N[d] + sc.floor[d]);
    if (f > 0) dW[f - 1] -= q;
    dW[f] += q;
  }
}

template <class T>
kernels::Population::State<T> ParticleChamber::population_state(const Ctx<T>& c, const T* N, const T* floor,
                                                                T* temp) const {
  kernels::Population::State<T> st;
  st.N = N;
  if (wet_) st.q[0] = &c.x(sW_);
  for (int k = 1; k < K_; ++k) st.q[(wet_ ? 1 : 0) + k - 1] = &c.x(sQ_[k - 1]);
  st.floor = floor;
  for (int i = 0; i < n_; ++i) temp[i] = c.x(sT_);
  st.fields[static_cast<int>(Field::kTemperature)] = temp;
  st.p = c.p;
  return st;
}

template <class T>
const T* ParticleChamber::discharge_fractions(const Ctx<T>& c) const {
  if (discharge_ != Discharge::kClassified) return nullptr;
  return classifier_.fractions(c.p, c.template ws<Work>().cls);
}

template <class T>
void ParticleChamber::outflows(const Ctx<T>& c, const T* frac) const {
  auto& sc = c.template ws<Work>().template scratch<T>();
  for (int k = 0; k < kOutlets; ++k) {
    const Outlet& o = outlet(k);
    if (!o.rate) continue;
    const T* f = &o == &discharge_out_ ? frac : nullptr;
    outlet_flows(n_, c.x(o.rate), f, &c.x(sM_), sc.om[k].data());
    if (wet_) outlet_flows(n_, c.x(o.rate), f, &c.x(sW_), sc.ow[k].data());
    for (int q = 1; q < K_; ++q) outlet_flows(n_, c.x(o.rate), f, &c.x(sQ_[q - 1]), sc.oq[k].data() + (q - 1) * n_);
  }
}

// The controlled discharge R for the controller's demand u: min(softplus(u), mdot_max) smoothed, or with a located
// valve 0, u or mdot_max by the valve's position, which the scene's events switch.
template <class T>
T ParticleChamber::valve_flow(const Ctx<T>& c, const T& u, const T& m_set, const T& tau_c) const {
  if (located_valve_) {
    const long pos = std::lround(value_of(c.par(p_valve_)));
    return pos == 0 ? T(0.0) : pos == 1 ? u : T(c.par(p_rmax_));
  }
  const T eps = kValveSmoothing * m_set / tau_c;
  const T open = softplus(u, eps);
  return open - softplus(T(open - c.par(p_rmax_)), eps);
}

template <class T>
Status ParticleChamber::eval(const Ctx<T>& c) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.template scratch<T>();
  const T* pm = particle_tables(c, w, sc, pp_, *grid_);
  const T* M = &c.x(sM_);
  const T* W = wet_ ? &c.x(sW_) : nullptr;
  // A class mass far below zero is no state of a bed (a Newton iterate of a steady-state solve that left the physical
  // branch, or an integrator step too long): refuse it, so that the step is cut. The integrator's own round-off in
  // emptied classes stays many orders of magnitude below the threshold.
  double held = 0.0, lowest = 0.0;
  if constexpr (std::is_same_v<T, double>) {  // vectorized: the order of the sum does not matter to the test
    const Eigen::Map<const Eigen::ArrayXd> m(M, n_);
    held = m.abs().sum(), lowest = std::min(0.0, m.minCoeff());
  } else {
    for (int i = 0; i < n_; ++i) held += std::abs(value_of(M[i])), lowest = std::min(lowest, value_of(M[i]));
  }
  if (lowest < -1e-6 * held) return Status::kRecoverable;
  for (int i = 0; i < n_; ++i) {
    sc.N[i] = M[i] / pm[i];
    sc.dM[i] = sc.dW[i] = T(0.0);
  }
  if (composed()) {
    class_numbers(c, pm, sc.N.data());
    std::fill(sc.dQ.begin(), sc.dQ.end(), T(0.0));
  }
  const T m_sus = spray_solids(c);
  if (composed() || !c.in_jacobian()) {  // the analytic part covers layering and the engine's mechanisms
    if (spray_ && composed())
      composed_growth(c, sc.N.data(), W, T(m_sus / pp_.component_density(c.shared, layer_)), sc.dM.data(), sc.dQ.data(),
                      sc.dW.data());
    else if (spray_)
      growth_rates(c, sc.N.data(), W, T(m_sus / pp_.envelope_density(c.shared)), sc.dM.data(), sc.dW.data());
    if (pop_.aggregation() || pop_.breakage()) {
      std::fill(sc.dN.begin(), sc.dN.end(), T(0.0));
      kernels::Population::Rates<T> r;
      r.dN = sc.dN.data();
      if (wet_) r.dq[0] = sc.dW.data();
      std::fill(sc.eq.begin(), sc.eq.end(), T(0.0));
      for (int k = 1; k < K_; ++k) r.dq[(wet_ ? 1 : 0) + k - 1] = sc.eq.data() + (k - 1) * n_;
      pop_.rates(*w.pop, population_state(c, sc.N.data(), sc.floor.data(), sc.temp.data()), r);
      if (composed())
        composed_engine(c, sc.dN.data(), sc.eq.data(), sc.dM.data(), sc.dQ.data());
      else
        for (int i = 0; i < n_; ++i) sc.dM[i] += pm[i] * sc.dN[i];
    }
  }
  // Outlet rates (fraction of a class leaving per second, times the classifier's fraction f_i).
  T exch_rate(0.0);
  if (exchange_.rate) {
    exch_rate = 1.0 / c.par(p_tau_);
    c.res(exchange_.rate) = c.x(exchange_.rate) - exch_rate;
  }
  const T* frac = discharge_fractions(c);
  outflows(c, frac);
  // What the inlets bring per class, read once: the controller sums it and every class row uses it.
  inlet_flows(c, sc.in_m.data(), sc.in_w.data(), sc.gather);
  if (discharge_ != Discharge::kNone) {
    if (controlled_) {
      const T mass = c.reduce(r_mass_, n_, [&](int i) { return M[i]; });
      const T weighted = frac ? c.reduce(r_tm_, n_, [&](int i) { return frac[i] * M[i]; }) : mass;
      const T fed = c.reduce(r_in_, n_, [&](int i) { return sc.in_m[i]; });
      const T& m_set = c.par(p_mset_);
      const T& tau_c = c.par(p_tauc_);
      const T u = fed + m_sus - exch_rate * mass + (mass - m_set) / tau_c;
      c.res(discharge_out_.rate) = c.x(discharge_out_.rate) - valve_flow(c, u, m_set, tau_c) / (weighted + kMassFloor);
    } else {
      c.res(discharge_out_.rate) = c.x(discharge_out_.rate) - c.par(p_k_);
    }
  }
  T surface(0.0), m_water(0.0);
  if (spray_ && wet_) {
    surface = c.reduce(r_surface_, n_, [&](int i) { return M[i] * sc.spm[i]; });
    m_water = c.par(p_spray_) * (1.0 - c.par(p_w_));
  }
  for (int i = 0; i < n_; ++i) {
    const T &in_m = sc.in_m[i], &in_w = sc.in_w[i];
    T out_m(0.0), out_w(0.0);
    for (int k = 0; k < kOutlets; ++k)
      if (outlet(k).rate) out_m += sc.om[k][i], out_w += sc.ow[k][i];
    c.res(sM_ + i) = c.xd(sM_ + i) - (sc.dM[i] + in_m - out_m);
    if (wet_) {
      // sprayed water lands in proportion to the class surface; first-order drying towards X_eq
      const T dep = spray_ ? T(m_water * M[i] * sc.spm[i] / (surface + kMassFloor)) : T(0.0);
      const T dry = drying_rate(c, M[i], W[i]);
      c.res(sW_ + i) = c.xd(sW_ + i) - (sc.dW[i] + in_w - out_w + dep - dry);
    }
  }
  if (composed()) composed_residuals(c);
  c.res(sT_) = c.x(sT_) - c.par(p_t_);
  if (sZero_) c.res(sZero_) = c.x(sZero_);
  return Status::kOk;
}

void ParticleChamber::analytic_jacobian(const Ctx<double>& c, double, JacobianSink& sink) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.sd;
  const double* pm = particle_tables(c, w, sc, pp_, *grid_);
  const double* M = &c.x(sM_);
  const double* W = wet_ ? &c.x(sW_) : nullptr;
  for (int i = 0; i < n_; ++i) sc.N[i] = M[i] / pm[i];
  if (spray_) {
    const double rho = pp_.envelope_density(c.shared);
    const double amount = spray_solids(c) / rho;
    const kernels::GrowthTerms<double> g{1, sc.ones.data(), &amount, true};
    fv_->fluxes(sc.N.data(), g, sc.F.data(), sc.donor.data());
    w.dF.resize(size_t(n_ + 1) * n_);
    fv_->flux_jacobian(sc.N.data(), g, w.dF.data());
    const int m0 = sM_.i, col0 = c.offset + sM_.i;
    // residual rows M_i' - rate: d rate / d M_l = sum_f c_if dF_f/dN_l / m_l, c_if the class's weight of face f
    for (int f = 0; f <= n_; ++f) {
      const double* dF = &w.dF[size_t(f) * n_];
      const int d = sc.donor[f];
      for (int l = 0; l < n_; ++l) {
        if (dF[l] == 0.0) continue;
        const double v = dF[l] / pm[l];
        if (f > 0) sink.add(m0 + f - 1, col0 + l, pm[f - 1] * v);
        if (f < n_)
          sink.add(m0 + f, col0 + l, -pm[f] * v);
        else
          sink.add(m0 + n_ - 1, col0 + l, -rho * grid_->upper_virtual() * v);
      }
      if (!W || d < 0 || f == n_) continue;
      // water flux q = F pi_d, pi_d = W_d / (N_d + floor_d): from class f - 1 (if any) to class f
      const double den = sc.N[d] + sc.floor[d], pi = W[d] / den;
      auto water = [&](int col, double v) {
        if (f > 0) sink.add(sW_.i + f - 1, col, v);
        sink.add(sW_.i + f, col, -v);
      };
      for (int l = 0; l < n_; ++l) {
        double v = dF[l] * pi;
        if (l == d) v -= sc.F[f] * pi / den;
        if (v != 0.0) water(col0 + l, v / pm[l]);
      }
      water(c.offset + sW_.i + d, sc.F[f] / den);
    }
  }
  if (pop_.aggregation() || pop_.breakage()) {
    if (!w.mapped) {
      kernels::Population::Map& m = w.map;
      m = {};
      for (int i = 0; i < n_; ++i) {
        m.N_col.push_back(c.offset + sM_.i + i), m.N_scale.push_back(1.0 / w.pm[i]);
        m.N_row.push_back(sM_.i + i), m.N_factor.push_back(-w.pm[i]);
        m.field_col[static_cast<int>(Field::kTemperature)].push_back(c.offset + sT_.i);
      }
      if (wet_) {
        m.q_col.assign(1, {}), m.q_row.assign(1, {});
        for (int i = 0; i < n_; ++i) m.q_col[0].push_back(c.offset + sW_.i + i), m.q_row[0].push_back(sW_.i + i);
      }
      w.mapped = true;
    }
    pop_.jacobian(*w.pop, population_state(c, sc.N.data(), sc.floor.data(), sc.temp.data()), w.map, sink);
  }
}

template <class T>
void ParticleChamber::init(InitCtx<T>& c) const {
  // Log-normal mass distribution over the cells, tails beyond the grid in the end classes; in T, so that initial
  // sensitivities to d50_0 and sigma_0 are exact. Or a measured table's (mapped in declare).
  const auto& de = grid_->diameter_edges();
  auto cdf = [&](int e) {
    using std::erfc, std::log;
    return T(0.5 * erfc(-log(de[e] / c.par(p_d50_)) / (log(c.par(p_sigma_)) * std::sqrt(2.0))));
  };
  T below(0.0);
  for (int i = 0; i < n_; ++i) {
    const T upto = psd_.table ? T(0.0) : i == n_ - 1 ? T(1.0) : cdf(i + 1);
    c.x(sM_ + i) = c.par(p_mass_) * (psd_.table ? T(psd_.psd.mass[i]) : upto - below);
    below = upto;
    if (wet_) c.x(sW_ + i) = c.x(sM_ + i) * c.par(p_x0_);
    for (StateId q : sQ_) c.x(q + i) = T(0.0);  // the initial hold-up is of the first component
  }
  c.x(sT_) = c.par(p_t_);
  if (sZero_) c.x(sZero_) = T(0.0);
  if (exchange_.rate) c.x(exchange_.rate) = 1.0 / c.par(p_tau_);
  if (discharge_out_.rate) c.x(discharge_out_.rate) = controlled_ ? T(0.0) : T(c.par(p_k_));
}

template <class T>
void ParticleChamber::outputs(const Ctx<T>& c) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.template scratch<T>();
  const T* pm = particle_tables(c, w, sc, pp_, *grid_);
  const T* M = &c.x(sM_);
  const auto& dp = grid_->diameter_pivots();
  T mass(0.0), water(0.0), mu[4] = {T(0.0), T(0.0), T(0.0), T(0.0)};
  if (composed()) class_numbers(c, pm, sc.N.data());
  for (int i = 0; i < n_; ++i) {
    mass += M[i];
    if (wet_) water += c.x(sW_ + i);
    const T N = composed() ? sc.N[i] : T(M[i] / pm[i]);
    T dk(1.0);
    for (int k = 0; k < 4; ++k) mu[k] += N * dk, dk *= dp[i];
  }
  c.out(o_mass_) = mass;
  if (wet_) c.out(o_moisture_) = water / (mass + kMassFloor);
  const double q[3] = {0.1, 0.5, 0.9};
  T dq[3];  // undefined for an empty bed
  kernels::characteristic_diameters_of_mass(grid_->diameter_edges(), M, q, 3, dq);
  for (int k = 0; k < 3; ++k) c.out(o_d_[k]) = dq[k];
  const bool any = mu[0] > 0.0;
  const T none = kernels::undefined_size<T>();  // an empty bed has no size
  c.out(o_d32_) = any ? T(mu[3] / mu[2]) : none;
  const T mean = any ? T(mu[1] / mu[0]) : none;
  c.out(o_dmean_) = mean;
  using std::sqrt;
  const T var = any ? T(mu[2] / mu[0] - mean * mean) : none;
  c.out(o_sigma_) = !any ? none : var > 0.0 ? T(sqrt(var)) : T(0.0);
  if (spray_)  // Eq. (7.33), paper 003, with mu_2 of the class pivots
    c.out(o_g_) =
        any ? T(2.0 * spray_solids(c) / (pp_.component_density(c.shared, layer_) * kernels::kPi * mu[2])) : T(0.0);
  c.out(o_particles_) = mu[0];
  const Boundary<T> b = boundary(c);  // and the outflows, read below
  auto outflow = [&](int k) {
    T m(0.0);
    for (int i = 0; i < n_; ++i) m += sc.om[k][i];
    return m;
  };
  if (discharge_out_.rate) c.out(o_dis_) = outflow(1);
  if (located_valve_) {  // the controller's demand u (eval), which the valve's events watch
    inlet_flows(c, sc.in_m.data(), sc.in_w.data(), sc.gather);
    T fed(0.0);
    for (int i = 0; i < n_; ++i) fed += sc.in_m[i];
    const T exch = exchange_.rate ? T(1.0 / c.par(p_tau_)) : T(0.0);
    c.out(o_demand_) = fed + spray_solids(c) - exch * mass + (mass - c.par(p_mset_)) / c.par(p_tauc_);
  }
  if (exchange_.rate) c.out(o_exch_) = outflow(0);
  c.out(o_top_) = mass > 0.0 ? T(M[n_ - 1] / mass) : T(0.0);
  c.out(o_hold_solids_) = mass;
  c.out(o_hold_water_) = water;
  c.out(o_hold_energy_) = (mass * c.sh(pp_.cp_s) + water * c.par(p_cpl_)) * (c.x(sT_) - props::kT0);
  c.out(o_heat_) = b.energy_in - b.h_spray;
  c.out(o_vapour_) = b.vapour;
  for (int i = 0; i < n_; ++i) {
    c.out(o_psd_d_ + i) = T(dp[i]);
    c.out(o_psd_m_ + i) = M[i];
  }
  if (o_outside_) c.out(o_outside_) = T(psd_.psd.outside());
  if (composed()) composed_outputs(c);
}

// Balance terms that cross the flowsheet's boundary here: the spray's solids, water and enthalpy, the vapour and its
// enthalpy, and the heat the gas supplies to hold the bed at T_bed, which is what closes the energy balance of the
// hold-up: Q = dH/dt - (enthalpy in with the inlets) + (enthalpy out with the outlets) - H_spray + H_vapour.
template <class T>
ParticleChamber::Boundary<T> ParticleChamber::boundary(const Ctx<T>& c) const {
  const T cp_s = c.sh(pp_.cp_s), cp_l = c.par(p_cpl_);
  const T& t = c.x(sT_);
  T vapour(0.0), h_in(0.0), h_out(0.0), dh(0.0), capacity(0.0);
  outflows(c, discharge_fractions(c));
  const auto& sc = c.template ws<Work>().template scratch<T>();
  for (int i = 0; i < n_; ++i) {
    const T wi = wet_ ? c.x(sW_ + i) : T(0.0);
    capacity += c.x(sM_ + i) * cp_s + wi * cp_l;
    dh += (c.xd(sM_ + i) * cp_s + (wet_ ? c.xd(sW_ + i) : T(0.0)) * cp_l) * (t - props::kT0);
    if (wet_) vapour += drying_rate(c, c.x(sM_ + i), wi);
    for (PortId p : inlets_) {
      const T& wf = c.port(p, solids::water(n_, i));
      h_in += (c.port(p, solids::mdot(i)) * cp_s + wf * cp_l) * (c.port(p, solids::T(n_)) - props::kT0);
      if (!wet_) vapour += wf;  // fed water evaporates at once
    }
    for (int k = 0; k < kOutlets; ++k)
      if (outlet(k).rate) h_out += (sc.om[k][i] * cp_s + sc.ow[k][i] * cp_l) * (t - props::kT0);
  }
  dh += capacity * c.xd(sT_);
  Boundary<T> b;
  b.h_spray = b.water_in = T(0.0);
  if (spray_) {
    b.water_in = c.par(p_spray_) * (1.0 - c.par(p_w_));
    if (!wet_) vapour += b.water_in;
    b.h_spray = c.par(p_spray_) * cp_l * (c.par(p_tspray_) - props::kT0);
  }
  b.vapour = vapour;
  b.h_vapour = vapour * props::vapour_enthalpy(t);
  b.energy_in = dh - h_in + h_out + b.h_vapour;  // = Q + H_spray
  return b;
}

template <class T>
void ParticleChamber::quad(const Ctx<T>& c) const {
  const Boundary<T> b = boundary(c);
  if (spray_) {
    c.r[q_solids_in_.i] = spray_solids(c);
    c.r[q_water_in_.i] = b.water_in;
    if (composed()) c.r[q_comp_in_.i] = spray_solids(c);
  }
  c.r[q_water_out_.i] = b.vapour;
  c.r[q_energy_in_.i] = b.energy_in;
  c.r[q_energy_out_.i] = b.h_vapour;
}

template Status ParticleChamber::eval(const Ctx<double>&) const;
template Status ParticleChamber::eval(const Ctx<Jet>&) const;
template void ParticleChamber::init(InitCtx<double>&) const;
template void ParticleChamber::init(InitCtx<Jet>&) const;
template void ParticleChamber::outputs(const Ctx<double>&) const;
template void ParticleChamber::outputs(const Ctx<Jet>&) const;
template void ParticleChamber::quad(const Ctx<double>&) const;
template void ParticleChamber::quad(const Ctx<Jet>&) const;

}  // namespace granuflow::units
