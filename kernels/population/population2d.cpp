#include "population/population2d.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <type_traits>
#include <unsupported/Eigen/FFT>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "registry.hpp"

namespace granuflow::kernels {

namespace {
using Complex = std::complex<double>;

}  // namespace

// Everything one run computes: the tables that depend on parameters only (refreshed when one changes) and the FFT
// work arrays.
struct Population2D::Work {
  std::vector<double> snapshot;  // the kernel's parameter values of the tables
  bool fresh = false;
  std::vector<double> K;                  // ns x ns, factor K_ik
  std::vector<double> phi;                // features per bin
  int terms = 0;                          // efficiency terms (convolution path)
  std::vector<double> h;                  // terms x bins
  double sign[kMaxEfficiencyTerms] = {};  // of each term
  Eigen::FFT<double> fft;                 // plans for length 2 nl, kept across calls
  std::vector<double> row;                // 2 nl, one padded row
  std::vector<Complex> spec;              // spectrum of one row, nl + 1
  std::vector<Complex> H;                 // terms x ns x (nl + 1): spectra of h_t N per solid row
  std::vector<Complex> S;                 // (ns + 2) x (nl + 1): births per target row, then leaving (number, solid)
  std::vector<Complex> P;                 // nl + 1
  std::vector<double> M;                  // terms x ns: sum_j h_t N per solid row
  std::vector<double> births, deaths;     // 2 nl, bins
};

Population2D::Population2D() = default;
Population2D::~Population2D() = default;
Population2D::Population2D(Population2D&&) noexcept = default;
Population2D& Population2D::operator=(Population2D&&) noexcept = default;

Population2D::WorkPtr Population2D::make_work() const { return WorkPtr(new Work()); }
void Population2D::WorkDeleter::operator()(Work* w) const { delete w; }

void Population2D::declare(UnitSpec& s, Settings& st, std::shared_ptr<const Grid2D> grid,
                           const Population2DOptions& o) {
  const auto& reg = registries();
  grid_ = std::move(grid);
  std::vector<std::string> names = reg.aggregation.names();
  names.insert(names.begin(), "none");
  const std::string agg = st.get_choice("aggregation", o.aggregation, names, "aggregation kernel");
  const std::string ev = st.get_choice(
      "aggregation_evaluation", "auto", {"auto", "convolution", "direct"},
      "aggregation by FFT convolutions along the liquid axis (kernels whose efficiency factors) or by the pair loop");
  evaluation_ = ev == "direct"        ? Evaluation2D::kDirect
                : ev == "convolution" ? Evaluation2D::kConvolution
                                      : Evaluation2D::kAuto;
  if (agg == "none") return;
  agg_ = reg.aggregation.create(agg, st.where());
  agg_->declare(st, o.agg_settings);
  const ClassNeeds needs = agg_->needs();
  for (int f = 0; f < kFields; ++f)
    if (needs.field(static_cast<Field>(f)) && static_cast<Field>(f) != Field::kLiquidFraction)
      throw ConfigError(st.where() + ".aggregation = '" + agg + "': the kernel reads the per-class " +
                        field_name(static_cast<Field>(f)) +
                        ", which a 2-D population does not have (its bins know their liquid content only)");
  if (needs.number)
    throw ConfigError(st.where() + ".aggregation = '" + agg +
                      "': the kernel reads the particle numbers, which the 2-D population does not support");
  first_ = static_cast<int>(s.params().size());
  std::vector<double> defaults;
  for (ParamSpec spec : agg_->params()) {
    defaults.push_back(spec.value);
    spec.name = o.agg_prefix + spec.name;
    if (s.param_index(spec.name) >= 0)
      throw ConfigError(st.where() + ": parameter '" + spec.name + "' of " + agg + " is declared twice in this unit");
    s.add_param(std::move(spec));
  }
  count_ = static_cast<int>(s.params().size()) - first_;
  targets_.setup(grid_->solid());
  // Whether the efficiency factors is a property of the kernel's form, not of its parameter values.
  double phi[kMaxFeatures] = {}, h[kMaxEfficiencyTerms], sign[kMaxEfficiencyTerms];
  const bool factors = agg_->efficiency_terms(phi, 1, defaults.data(), h, sign) > 0;
  if (evaluation_ == Evaluation2D::kConvolution && !factors)
    throw ConfigError(st.where() + ".aggregation_evaluation = 'convolution': kernel '" + agg +
                      "' has an efficiency that does not factor into products; use auto or direct");
  conv_ = factors && evaluation_ != Evaluation2D::kDirect;
}

void Population2D::configure(Work& w, const double* p, const std::string& where) const {
  if (!agg_) return;
  const Grid& g = grid_->solid();
  ClassState<double> cs;
  cs.n = g.size();
  cs.volume = g.pivots().data();
  cs.diameter = g.diameter_pivots().data();
  agg_->check(cs, p + first_, where);
  w.fresh = false;
  refresh(w, p);
  const int nl = grid_->nl(), ns = grid_->ns();
  w.row.assign(2 * size_t(nl), 0.0);
  w.spec.assign(nl + 1, Complex(0.0));
  w.P.assign(nl + 1, Complex(0.0));
  w.births.assign(2 * size_t(nl), 0.0);
  w.deaths.assign(grid_->size(), 0.0);
  w.fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  w.S.assign(size_t(ns + 2) * (nl + 1), Complex(0.0));
}

// Re-evaluates K, the features and the efficiency terms when a kernel parameter value changed since the last time.
void Population2D::refresh(Work& w, const double* p) const {
  bool same = w.fresh && int(w.snapshot.size()) == count_;
  for (int k = 0; same && k < count_; ++k) same = w.snapshot[k] == p[first_ + k];
  if (same) return;
  w.snapshot.assign(p + first_, p + first_ + count_);
  w.fresh = true;
  const Grid& g = grid_->solid();
  const int ns = g.size(), n = grid_->size();
  ClassState<double> cs;
  cs.n = ns;
  cs.volume = g.pivots().data();
  cs.diameter = g.diameter_pivots().data();
  w.K.resize(size_t(ns) * ns);
  agg_->factor(cs, p + first_, w.K.data());
  const int m = agg_->n_features();
  ClassState<double> bins;
  bins.n = n;
  bins.volume = grid_->total_volumes().data();
  bins.diameter = grid_->diameters().data();
  bins.fields[static_cast<int>(Field::kLiquidFraction)] = grid_->liquid_contents().data();
  w.phi.assign(size_t(n) * std::max(m, 1), 0.0);
  if (m > 0) agg_->features(bins, p + first_, w.phi.data());
  w.h.assign(size_t(kMaxEfficiencyTerms) * n, 0.0);
  w.terms = agg_->efficiency_terms(w.phi.data(), n, p + first_, w.h.data(), w.sign);
}

void Population2D::aggregation_rates(Work& w, const double* N, const double* p, double* dN, double* out) const {
  if (!agg_) return;
  refresh(w, p);
  if (conv_)
    convolve(w, N, dN, out);
  else
    direct(w, N, p, dN, out);
}

void Population2D::aggregation_rates(Work& w, const Jet* N, const Jet* p, Jet* dN, Jet* out) const {
  if (!agg_) return;
  direct(w, N, p, dN, out);
}

void Population2D::aggregation_direct(Work& w, const double* N, const double* p, double* dN, double* out) const {
  if (!agg_) return;
  refresh(w, p);
  direct(w, N, p, dN, out);
}

// Every pair of bins a <= b: the event rate beta_ab N_a N_b (half for a = b), the partners removed, the aggregate
// split between the solid pivots around s_i + s_k at liquid class j + m (paper 002, Eqs. (8)-(10)).
template <class T>
void Population2D::direct(Work& w, const T* N, const T* p, T* dN, T* out) const {
  const Grid2D& g = *grid_;
  const int ns = g.ns(), nl = g.nl(), n = g.size(), m = agg_->n_features();
  const double dl = g.liquid_step();
  const T* K;
  const T* phi;
  std::vector<T> Kj, phij;
  const T* kp = p + first_;
  if constexpr (std::is_same_v<T, double>) {
    K = w.K.data(), phi = w.phi.data();
  } else {
    const Grid& sg = g.solid();
    ClassState<Jet> cs;
    cs.n = ns, cs.volume = sg.pivots().data(), cs.diameter = sg.diameter_pivots().data();
    Kj.resize(size_t(ns) * ns);
    agg_->factor(cs, kp, Kj.data());
    std::vector<Jet> lc(g.liquid_contents().begin(), g.liquid_contents().end());
    ClassState<Jet> bins;
    bins.n = n, bins.volume = g.total_volumes().data(), bins.diameter = g.diameters().data();
    bins.fields[static_cast<int>(Field::kLiquidFraction)] = lc.data();
    phij.assign(size_t(n) * std::max(m, 1), Jet(0.0));
    if (m > 0) agg_->features(bins, kp, phij.data());
    K = Kj.data(), phi = phij.data();
  }
  for (int a = 0; a < n; ++a) {
    if (is_empty(N[a])) continue;
    const int i = a / nl, j = a % nl;
    T death_a(0.0);
    for (int b = a; b < n; ++b) {
      if (is_empty(N[b])) continue;
      const int k = b / nl, l = b % nl;
      T beta = K[size_t(i) * ns + k];
      if (m > 0) beta *= agg_->efficiency(phi + size_t(a) * m, phi + size_t(b) * m, kp);
      const T rate = (a == b ? 0.5 : 1.0) * beta * N[a] * N[b];
      death_a += rate;
      dN[b] -= rate;
      const FixedPivotAggregation::Target& t = targets_.target(pair_index(std::min(i, k), std::max(i, k), ns));
      const double v = targets_.volume(pair_index(std::min(i, k), std::max(i, k), ns));
      const int L = j + l;
      const int rows[2] = {t.lo, t.hi};
      const double wn[2] = {t.w_lo, t.w_hi}, fv[2] = {t.f_lo * v, t.f_hi * v};
      for (int side = 0; side < 2; ++side) {
        if (wn[side] == 0.0 && fv[side] == 0.0) continue;
        if (rows[side] >= 0 && L < nl) {
          dN[rows[side] * nl + L] += wn[side] * rate;
        } else {
          out[kOut2Number] += wn[side] * rate;
          out[kOut2Solid] += fv[side] * rate;
          out[kOut2Liquid] += wn[side] * (L * dl) * rate;
        }
      }
    }
    dN[a] -= death_a;
  }
}

void Population2D::factored_deaths(Work& w, const double* N, double* d) const {
  const Grid2D& g = *grid_;
  const int ns = g.ns(), nl = g.nl(), T = w.terms;
  w.M.assign(size_t(T) * ns, 0.0);
  for (int t = 0; t < T; ++t)
    for (int a = 0; a < g.size(); ++a) w.M[size_t(t) * ns + a / nl] += w.h[size_t(t) * g.size() + a] * N[a];
  std::vector<double> KM(size_t(T) * ns, 0.0);
  for (int t = 0; t < T; ++t)
    for (int i = 0; i < ns; ++i) {
      double s = 0;
      for (int k = 0; k < ns; ++k) s += w.K[size_t(i) * ns + k] * w.M[size_t(t) * ns + k];
      KM[size_t(t) * ns + i] = w.sign[t] * s;
    }
  for (int a = 0; a < g.size(); ++a) {
    double s = 0;
    for (int t = 0; t < T; ++t) s += w.h[size_t(t) * g.size() + a] * KM[size_t(t) * ns + a / nl];
    d[a] = s;
  }
}

void Population2D::death_rates(Work& w, const double* N, const double* p, double* d) const {
  const int n = grid_->size();
  std::fill(d, d + n, 0.0);
  if (!agg_) return;
  refresh(w, p);
  if (w.terms > 0) return factored_deaths(w, N, d);
  const int ns = grid_->ns(), nl = grid_->nl(), m = agg_->n_features();
  const double* kp = p + first_;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      double beta = w.K[size_t(a / nl) * ns + b / nl];
      if (m > 0) beta *= agg_->efficiency(&w.phi[size_t(a) * m], &w.phi[size_t(b) * m], kp);
      d[a] += beta * N[b];
    }
}

// The pair loop over solid classes only: for the pair (i, k) and efficiency term t, the births along the liquid
// axis are the convolution of the rows h_t N_i and h_t N_k, a product of their spectra. Spectra are summed per target
// row (with the fixed-pivot weights) and transformed back once per row.
void Population2D::convolve(Work& w, const double* N, double* dN, double* out) const {
  const Grid2D& g = *grid_;
  const int ns = g.ns(), nl = g.nl(), n = g.size(), T = w.terms, nf = nl + 1;
  const double dl = g.liquid_step();
  // deaths from the factored sums
  factored_deaths(w, N, w.deaths.data());
  for (int a = 0; a < n; ++a) dN[a] -= N[a] * w.deaths[a];
  // spectra of the rows h_t N_i (zero-padded to 2 nl: no wrap-around of l_j + l_m)
  w.H.resize(size_t(T) * ns * nf);
  std::vector<char> empty(size_t(T) * ns, 1);
  for (int t = 0; t < T; ++t)
    for (int i = 0; i < ns; ++i) {
      const double* h = &w.h[size_t(t) * n + size_t(i) * nl];
      bool any = false;
      for (int j = 0; j < nl; ++j) {
        w.row[j] = h[j] * N[size_t(i) * nl + j];
        any = any || w.row[j] != 0.0;
      }
      std::fill(w.row.begin() + nl, w.row.end(), 0.0);
      if (!any) continue;
      empty[size_t(t) * ns + i] = 0;
      w.fft.fwd(w.spec, w.row);
      std::copy(w.spec.begin(), w.spec.begin() + nf, w.H.begin() + (size_t(t) * ns + i) * nf);
    }
  std::fill(w.S.begin(), w.S.end(), Complex(0.0));
  Complex* leave_n = &w.S[size_t(ns) * nf];
  Complex* leave_s = &w.S[size_t(ns + 1) * nf];
  for (int i = 0; i < ns; ++i)
    for (int k = i; k < ns; ++k) {
      const size_t pr = pair_index(i, k, ns);
      const double Kh = (i == k ? 0.5 : 1.0) * w.K[size_t(i) * ns + k];
      if (Kh == 0.0) continue;
      const FixedPivotAggregation::Target& tg = targets_.target(pr);
      const double v = targets_.volume(pr);
      bool any = false;
      std::fill(w.P.begin(), w.P.end(), Complex(0.0));
      for (int t = 0; t < T; ++t) {
        if (empty[size_t(t) * ns + i] || empty[size_t(t) * ns + k]) continue;
        any = true;
        const Complex* a = &w.H[(size_t(t) * ns + i) * nf];
        const Complex* b = &w.H[(size_t(t) * ns + k) * nf];
        const double c = Kh * w.sign[t];
        for (int f = 0; f < nf; ++f) w.P[f] += c * (a[f] * b[f]);
      }
      if (!any) continue;
      const int rows[2] = {tg.lo, tg.hi};
      const double wn[2] = {tg.w_lo, tg.w_hi}, fv[2] = {tg.f_lo * v, tg.f_hi * v};
      for (int side = 0; side < 2; ++side) {
        if (wn[side] == 0.0 && fv[side] == 0.0) continue;
        if (rows[side] >= 0) {
          Complex* s = &w.S[size_t(rows[side]) * nf];
          for (int f = 0; f < nf; ++f) s[f] += wn[side] * w.P[f];
        } else {
          for (int f = 0; f < nf; ++f) leave_n[f] += wn[side] * w.P[f], leave_s[f] += fv[side] * w.P[f];
        }
      }
    }
  // back along the liquid axis: births of row r at liquid class L, beyond nl - 1 they leave the grid. Births are
  // non-negative; the inverse FFT leaves round-off of both signs (1e-16 of the row's largest) where there are none,
  // which would take empty bins below zero: cut at zero
  for (int r = 0; r < ns + 2; ++r) {
    const Complex* s = &w.S[size_t(r) * nf];
    bool any = false;
    for (int f = 0; f < nf && !any; ++f) any = s[f] != Complex(0.0);
    if (!any) continue;
    std::copy(s, s + nf, w.spec.begin());
    w.fft.inv(w.births, w.spec, 2 * nl);
    for (double& x : w.births) x = std::max(x, 0.0);
    if (r < ns) {
      const double sr = g.solid().pivot(r);
      for (int L = 0; L < nl; ++L) dN[size_t(r) * nl + L] += w.births[L];
      for (int L = nl; L < 2 * nl; ++L) {
        out[kOut2Number] += w.births[L];
        out[kOut2Solid] += sr * w.births[L];
        out[kOut2Liquid] += L * dl * w.births[L];
      }
    } else if (r == ns) {
      for (int L = 0; L < 2 * nl; ++L) out[kOut2Number] += w.births[L], out[kOut2Liquid] += L * dl * w.births[L];
    } else {
      for (int L = 0; L < 2 * nl; ++L) out[kOut2Solid] += w.births[L];
    }
  }
}

// Aggregation is bilinear in N with a constant beta: d(rate of pair a <= b)/dN_a = c N_b, /dN_b = c N_a (2 c N_a when
// a = b), placed on the rows the pair's rate enters.
void Population2D::aggregation_jacobian(Work& w, const double* N, const double* p, const std::vector<int>& rows,
                                        const std::vector<int>& cols, double factor, JacobianSink& sink) const {
  if (!agg_) return;
  refresh(w, p);
  const Grid2D& g = *grid_;
  const int ns = g.ns(), nl = g.nl(), n = g.size(), m = agg_->n_features(), T = w.terms;
  const double dl = g.liquid_step();
  const double* kp = p + first_;
  const int r_on = rows[n + kOut2Number], r_os = rows[n + kOut2Solid], r_ol = rows[n + kOut2Liquid];
  for (int a = 0; a < n; ++a) {
    const int i = a / nl, j = a % nl;
    for (int b = a; b < n; ++b) {
      if (N[a] == 0.0 && N[b] == 0.0) continue;
      const int k = b / nl, l = b % nl;
      double E = 1.0;
      if (T > 0) {
        E = 0.0;
        for (int t = 0; t < T; ++t) E += w.sign[t] * w.h[size_t(t) * n + a] * w.h[size_t(t) * n + b];
      } else if (m > 0) {
        E = agg_->efficiency(&w.phi[size_t(a) * m], &w.phi[size_t(b) * m], kp);
      }
      const double c = (a == b ? 0.5 : 1.0) * w.K[size_t(i) * ns + k] * E * factor;
      if (c == 0.0) continue;
      // the rate's derivatives: by column
      const int nc = a == b ? 1 : 2;
      const int col[2] = {cols[a], cols[b]};
      const double d[2] = {a == b ? 2.0 * c * N[a] : c * N[b], c * N[a]};
      const size_t pr = pair_index(std::min(i, k), std::max(i, k), ns);
      const FixedPivotAggregation::Target& t = targets_.target(pr);
      const double v = targets_.volume(pr);
      const int L = j + l;
      for (int q = 0; q < nc; ++q) {
        if (d[q] == 0.0) continue;
        sink.add(rows[a], col[q], -d[q]);
        sink.add(rows[b], col[q], -d[q]);
        const int tr[2] = {t.lo, t.hi};
        const double wn[2] = {t.w_lo, t.w_hi}, fv[2] = {t.f_lo * v, t.f_hi * v};
        for (int side = 0; side < 2; ++side) {
          if (wn[side] == 0.0 && fv[side] == 0.0) continue;
          if (tr[side] >= 0 && L < nl) {
            sink.add(rows[size_t(tr[side]) * nl + L], col[q], wn[side] * d[q]);
          } else {
            if (r_on >= 0) sink.add(r_on, col[q], wn[side] * d[q]);
            if (r_os >= 0) sink.add(r_os, col[q], fv[side] * d[q]);
            if (r_ol >= 0) sink.add(r_ol, col[q], wn[side] * L * dl * d[q]);
          }
        }
      }
    }
  }
}

template void Population2D::direct<double>(Work&, const double*, const double*, double*, double*) const;
template void Population2D::direct<Jet>(Work&, const Jet*, const Jet*, Jet*, Jet*) const;

}  // namespace granuflow::kernels
