#include "discretization/fv_growth.hpp"

#include <cmath>
#include <vector>

namespace granuflow::kernels {
namespace {

// Koren's limited slope (Koren 1993) from the downwind jump a and the upwind jump b (both scaled to the cell width):
// the kappa = 1/3 reconstruction (2a + b)/3, third-order upwind-biased where the solution is smooth, limited to
// min(2|a|, 2|b|) with the common sign and 0 at extrema; da, db its derivatives.
template <class T, bool kDerivatives = true>
T koren(const T& a, const T& b, double& da, double& db) {
  da = db = 0.0;
  if (!(a * b > 0.0)) return T(0.0);
  const double s = a > 0.0 ? 1.0 : -1.0;
  const T abs_a = s * a, abs_b = s * b;
  const T third = (2.0 * abs_a + abs_b) / 3.0;
  if (2.0 * abs_b <= third && 2.0 * abs_b <= 2.0 * abs_a) {
    db = 2.0;
    return 2.0 * b;
  }
  if (third <= 2.0 * abs_a) {
    da = 2.0 / 3.0, db = 1.0 / 3.0;
    return (2.0 * a + b) / 3.0;
  }
  da = 2.0;
  return 2.0 * a;
}

// van Albada's slope ab (a + b) / (a^2 + b^2) from the same jumps, and its derivatives.
template <class T, bool kDerivatives = true>
T van_albada(const T& a, const T& b, double& da, double& db) {
  const double av = value_of(a), bv = value_of(b), q = av * av + bv * bv;
  da = db = 0.0;
  if (!(q > 0.0)) return T(0.0);
  if constexpr (!kDerivatives) return a * b * (a + b) / (a * a + b * b);
  const double num = av * bv * (av + bv);
  da = (bv * (2.0 * av + bv) * q - 2.0 * av * num) / (q * q);
  db = (av * (av + 2.0 * bv) * q - 2.0 * bv * num) / (q * q);
  return a * b * (a + b) / (a * a + b * b);
}

}  // namespace

void FvGrowth::setup(const Grid& g) {
  grid_ = &g;
  n_ = g.size();
  const auto& de = g.diameter_edges();
  d_face_ = de;
  width_.resize(n_), cplus_.assign(n_, 0.0), cminus_.assign(n_, 0.0);
  std::vector<double> centre(n_);
  for (int i = 0; i < n_; ++i) width_[i] = de[i + 1] - de[i], centre[i] = 0.5 * (de[i] + de[i + 1]);
  for (int i = 0; i < n_; ++i) {
    if (i + 1 < n_) cplus_[i] = width_[i] / (centre[i + 1] - centre[i]);
    if (i > 0) cminus_[i] = width_[i] / (centre[i] - centre[i - 1]);
  }
  dx_face_.resize(n_ + 1);
  for (int f = 0; f <= n_; ++f) dx_face_[f] = g.pivot_ext(f) - g.pivot_ext(f - 1);
}

template <class T, bool kDerivatives, class Dens>
FvGrowth::Face<T> FvGrowth::face(Dens dens, int f, bool upward) const {
  Face<T> r{T(0.0), {-1, -1, -1}, {0, 0, 0}};
  // Donor cell and the neighbours downwind (towards the face) and upwind; mirrored for downward growth.
  const int donor = upward ? f - 1 : f;
  if (donor < 0 || donor >= n_) return r;  // inflow through the boundary: none
  const int down = upward ? donor + 1 : donor - 1, up = upward ? donor - 1 : donor + 1;
  const T nd = dens(donor);
  r.phi = nd;
  r.cols[0] = donor;
  r.d[0] = 1.0 / width_[donor];
  if (limiter_ == Limiter::kNone || down < 0 || down >= n_ || up < 0 || up >= n_) return r;
  const double cd = upward ? cplus_[donor] : cminus_[donor], cu = upward ? cminus_[donor] : cplus_[donor];
  const T a = (dens(down) - nd) * cd, b = (nd - dens(up)) * cu;
  double da, db;
  r.phi += 0.5 * (limiter_ == Limiter::kKoren ? koren<T, kDerivatives>(a, b, da, db)
                                              : van_albada<T, kDerivatives>(a, b, da, db));
  if constexpr (!kDerivatives) return r;
  // phi = nd + sigma(a, b)/2, a = (n_down - nd) cd, b = (nd - n_up) cu
  r.cols[1] = down, r.cols[2] = up;
  r.d[0] += 0.5 * (-da * cd + db * cu) / width_[donor];
  r.d[1] = 0.5 * da * cd / width_[down];
  r.d[2] = -0.5 * db * cu / width_[up];
  return r;
}

template <class T, class Phi>
void FvGrowth::term_scales(const GrowthTerms<T>& g, Phi phi, TermScale<T>* ts) const {
  const int nf = n_ + 1;
  for (int k = 0; k < g.terms; ++k) {
    ts[k] = {T(g.amount[k]), T(0.0), true};
    if (!g.normalized) continue;
    const T* s = g.shape + size_t(k) * nf;
    T integral(0.0);
    for (int f = 0; f < nf; ++f) integral += s[f] * phi(f) * dx_face_[f];
    if (!(integral > 0.0)) {  // no particles to grow on
      ts[k] = {T(0.0), T(0.0), false};
      continue;
    }
    ts[k].inv = 1.0 / integral;
    ts[k].value = g.amount[k] * ts[k].inv;
  }
}

template <class T>
T FvGrowth::rate_at(const GrowthTerms<T>& g, const TermScale<T>* ts, int f) const {
  const int nf = n_ + 1;
  T G(0.0);
  for (int k = 0; k < g.terms; ++k)
    if (ts[k].grows) G += ts[k].value * g.shape[size_t(k) * nf + f];
  return G;
}

template <class T>
void FvGrowth::growth_at_faces(const std::vector<Face<T>>& fc, const GrowthTerms<T>& g, std::vector<T>& G,
                               std::vector<T>& inv_integral) const {
  const int nf = n_ + 1;
  std::vector<TermScale<T>> ts(g.terms);
  term_scales(
      g, [&](int f) { return fc[f].phi; }, ts.data());
  G.resize(nf);
  for (int f = 0; f < nf; ++f) G[f] = rate_at(g, ts.data(), f);
  inv_integral.resize(g.terms);
  for (int k = 0; k < g.terms; ++k) inv_integral[k] = ts[k].inv;
}

template <class T>
void FvGrowth::faces_and_growth(const T* N, const GrowthTerms<T>& g, std::vector<Face<T>>& fc, std::vector<T>& G,
                                std::vector<T>& inv_integral) const {
  const int nf = n_ + 1;
  fc.resize(nf);
  auto dens = [this, N](int k) -> T { return N[k] / width_[k]; };
  if (g.normalized) {
    // Volume-normalized laws grow (a_k >= 0, s_k >= 0): upwind from below.
    for (int f = 0; f < nf; ++f) fc[f] = face<T, true>(dens, f, true);
    growth_at_faces(fc, g, G, inv_integral);
  } else {
    growth_at_faces(fc, g, G, inv_integral);  // phi is not needed for absolute laws
    for (int f = 0; f < nf; ++f) fc[f] = face<T, true>(dens, f, !(G[f] < 0.0));
  }
}

// The residual's path: face values only (the derivatives d[] serve flux_jacobian alone) and no work arrays, F
// holding the face densities until the growth rates are known; the same operations in the same order as
// faces_and_growth, so both paths agree to the bit.
template <class T>
T FvGrowth::flux_values(const T* N, const GrowthTerms<T>& g, T* F, int* donor) const {
  const int nf = n_ + 1;
  constexpr int kTerms = 4;  // the terms' scales of up to this many on the stack
  TermScale<T> stack[kTerms];
  std::vector<TermScale<T>> heap(g.terms > kTerms ? g.terms : 0);
  TermScale<T>* ts = g.terms > kTerms ? heap.data() : stack;
  if (g.normalized) {
    // Each cell's density once, into F (nf > n); then the faces from the top down, each written over a cell that no
    // lower face reads (face f reads cells f - 2 to f).
    for (int k = 0; k < n_; ++k) F[k] = N[k] / width_[k];
    for (int f = nf - 1; f >= 0; --f) {
      const Face<T> fc = face<T, false>([F](int k) -> T { return F[k]; }, f, true);
      F[f] = fc.phi, donor[f] = fc.cols[0];
    }
    term_scales(
        g, [&](int f) { return F[f]; }, ts);
    for (int f = 0; f < nf; ++f) F[f] = rate_at(g, ts, f) * F[f];
  } else {
    term_scales(
        g, [](int) { return T(0.0); }, ts);  // absolute laws read no face density
    for (int f = 0; f < nf; ++f) {
      const T G = rate_at(g, ts, f);
      const Face<T> fc = face<T, false>([this, N](int k) -> T { return N[k] / width_[k]; }, f, !(G < 0.0));
      F[f] = G * fc.phi, donor[f] = fc.cols[0];
    }
  }
  T W(0.0);
  for (int f = 0; f < nf; ++f) W += F[f] * dx_face_[f];
  return W;
}

// flux_values for doubles and a volume-normalized law with a smooth or no limiter (layering): the face densities
// from an array of cell densities in one vector loop over the interior faces, the rates term by term over the faces.
// Per face the same operations in the same order as flux_values (van_albada's a b (a + b) / (a^2 + b^2) with its
// q = a^2 + b^2 test, nd + 0.5 sigma, G = 0 + the growing terms in order, F = G phi), so both paths agree to the bit.
double FvGrowth::normalized_fluxes(const double* N, const GrowthTerms<double>& g, double* F, int* donor) const {
  const int n = n_, nf = n_ + 1;
  thread_local std::vector<double> rho, G;
  rho.resize(n), G.resize(nf);
  for (int k = 0; k < n; ++k) rho[k] = N[k] / width_[k];
  F[0] = 0.0, donor[0] = -1;  // inflow through the bottom face: none
  for (int f = 1; f < nf; ++f) F[f] = rho[f - 1], donor[f] = f - 1;
  if (limiter_ == Limiter::kVanAlbada && n >= 3) {
    const double *r = rho.data(), *cp = cplus_.data(), *cm = cminus_.data();
    for (int f = 2; f < n; ++f) {  // faces with cells on both sides of the donor f - 1
      const double nd = r[f - 1];
      const double a = (r[f] - nd) * cp[f - 1], b = (nd - r[f - 2]) * cm[f - 1];
      const double q = a * a + b * b;
      const double sigma = q > 0.0 ? a * b * (a + b) / (a * a + b * b) : 0.0;
      F[f] = nd + 0.5 * sigma;
    }
  }
  constexpr int kTerms = 4;
  TermScale<double> stack[kTerms];
  std::vector<TermScale<double>> heap(g.terms > kTerms ? g.terms : 0);
  TermScale<double>* ts = g.terms > kTerms ? heap.data() : stack;
  term_scales(
      g, [&](int f) { return F[f]; }, ts);
  std::fill(G.begin(), G.end(), 0.0);
  for (int k = 0; k < g.terms; ++k) {
    if (!ts[k].grows) continue;
    const double v = ts[k].value, *s = g.shape + size_t(k) * nf;
    for (int f = 0; f < nf; ++f) G[f] += v * s[f];
  }
  for (int f = 0; f < nf; ++f) F[f] = G[f] * F[f];
  double W = 0.0;
  for (int f = 0; f < nf; ++f) W += F[f] * dx_face_[f];
  return W;
}

double FvGrowth::fluxes(const double* N, const GrowthTerms<double>& g, double* F, int* donor) const {
  if (g.normalized && limiter_ != Limiter::kKoren) return normalized_fluxes(N, g, F, donor);
  return flux_values(N, g, F, donor);
}
Jet FvGrowth::fluxes(const Jet* N, const GrowthTerms<Jet>& g, Jet* F, int* donor) const {
  return flux_values(N, g, F, donor);
}

void FvGrowth::flux_jacobian(const double* N, const GrowthTerms<double>& g, double* dF) const {
  const int n = n_, nf = n_ + 1;
  std::vector<Face<double>> fc;
  std::vector<double> G, inv;
  faces_and_growth(N, g, fc, G, inv);
  // dF_f/dN_l = G_f dphi_f/dN_l + phi_f dG_f/dN_l; the second term only for normalized laws, where
  // dG_f/dN_l = -sum_k a_k s_kf / I_k^2 dI_k/dN_l and dI_k/dN_l = sum_f' s_kf' dx_f' dphi_f'/dN_l.
  std::fill(dF, dF + size_t(nf) * n, 0.0);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c)
      if (fc[f].cols[c] >= 0) dF[size_t(f) * n + fc[f].cols[c]] += G[f] * fc[f].d[c];
  if (g.normalized) {
    std::vector<double> dI(n);
    for (int k = 0; k < g.terms; ++k) {
      if (inv[k] == 0.0) continue;
      const double* s = g.shape + size_t(k) * nf;
      std::fill(dI.begin(), dI.end(), 0.0);
      for (int f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c)
          if (fc[f].cols[c] >= 0) dI[fc[f].cols[c]] += s[f] * dx_face_[f] * fc[f].d[c];
      const double coef = -g.amount[k] * inv[k] * inv[k];
      for (int f = 0; f < nf; ++f) {
        const double w = coef * s[f] * fc[f].phi;
        if (w == 0.0) continue;
        double* row = &dF[size_t(f) * n];
        for (int l = 0; l < n; ++l) row[l] += w * dI[l];
      }
    }
  }
}

}  // namespace granuflow::kernels
