#include "discretization/fv_growth.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

namespace granuflow::kernels {
namespace {

// Koren's limited slope (Koren 1993) from the downwind jump a and the upwind jump b (both scaled to the cell width):
// the kappa = 1/3 reconstruction (2a + b)/3, third-order upwind-biased where the solution is smooth, limited to
// min(2|a|, 2|b|) with the common sign and 0 at extrema; da, db its derivatives. The common sign is tested on the
// signs, not on a b > 0, which underflows for jumps below 1e-154 (the far tail of a distribution).
template <class T>
T koren(const T& a, const T& b, double& da, double& db) {
  da = db = 0.0;
  if (!((a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0))) return T(0.0);
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

// van Albada's slope ab (a + b) / (a^2 + b^2) from the same jumps (0 where a = b = 0), and with kDerivatives its
// derivatives; a select, so that the loop over the faces stays a vector loop for doubles.
// The slope is a ratio of third- to second-degree terms and its derivatives of fourth-degree ones: for jumps below
// about 1e-77 (the far tail of a narrow distribution on a wide grid) these underflow, to 0 / 0 under flush-to-zero,
// and a NaN Jacobian stopped the run at its start. The slope is homogeneous of degree 1, so jumps below kSmall are
// scaled by the larger one first and the slope scaled back; above it m = 1 and every operation gives the bits of the
// plain formulas (x / 1 and 1 * s are exact, for Jets too).
template <class T, bool kDerivatives>
T van_albada(const T& a, const T& b, double& da, double& db) {
  constexpr double kSmall = 1e-50;  // fourth-degree terms of larger jumps stay above 1e-200
  const double big = std::max(std::fabs(value_of(a)), std::fabs(value_of(b)));
  const double m = big > 0.0 && big < kSmall ? big : 1.0;
  const T x = a / m, y = b / m;
  const double xv = value_of(x), yv = value_of(y), q = xv * xv + yv * yv;
  da = db = 0.0;
  if constexpr (kDerivatives) {
    if (q > 0.0) {
      const double num = xv * yv * (xv + yv);
      da = (yv * (2.0 * xv + yv) * q - 2.0 * xv * num) / (q * q);
      db = (xv * (xv + 2.0 * yv) * q - 2.0 * yv * num) / (q * q);
    }
  }
  return q > 0.0 ? T(m * (x * y * (x + y) / (x * x + y * y))) : T(0.0);
}

// The density at a face whose donor (density nd) has neighbours on both sides (densities n_down towards the face,
// n_up away from it): nd plus half the limiter's slope of the jumps scaled by cd and cu; nd itself without a limiter.
// Every path of the scheme computes a face's density here, with the same operations in the same order.
template <Limiter L, bool kDerivatives, class T>
inline T face_density(const T& nd, const T& n_down, const T& n_up, double cd, double cu, double& da, double& db) {
  da = db = 0.0;
  if constexpr (L == Limiter::kNone) {
    return nd;
  } else {
    const T a = (n_down - nd) * cd, b = (nd - n_up) * cu;
    if constexpr (L == Limiter::kKoren)
      return nd + 0.5 * koren(a, b, da, db);
    else
      return nd + 0.5 * van_albada<T, kDerivatives>(a, b, da, db);
  }
}

// f(std::integral_constant<Limiter, L>) for the run-time limiter l: the scheme's paths are templates on it.
template <class F>
decltype(auto) with_limiter(Limiter l, F&& f) {
  switch (l) {
    case Limiter::kKoren:
      return f(std::integral_constant<Limiter, Limiter::kKoren>{});
    case Limiter::kVanAlbada:
      return f(std::integral_constant<Limiter, Limiter::kVanAlbada>{});
    default:
      return f(std::integral_constant<Limiter, Limiter::kNone>{});
  }
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
  for (int f = 0; f < n_ + 1; ++f) dx_face_[f] = g.pivot_ext(f) - g.pivot_ext(f - 1);
}

FvGrowth::Stencil FvGrowth::stencil(int f, bool upward) const {
  Stencil s;
  // Donor cell and the neighbours downwind (towards the face) and upwind; mirrored for downward growth.
  s.donor = upward ? f - 1 : f;
  if (s.donor < 0 || s.donor >= n_) {  // inflow through the boundary: none
    s.donor = -1;
    return s;
  }
  s.down = upward ? s.donor + 1 : s.donor - 1, s.up = upward ? s.donor - 1 : s.donor + 1;
  s.full = limiter_ != Limiter::kNone && s.down >= 0 && s.down < n_ && s.up >= 0 && s.up < n_;
  s.cd = upward ? cplus_[s.donor] : cminus_[s.donor], s.cu = upward ? cminus_[s.donor] : cplus_[s.donor];
  return s;
}

// The one loop over the faces: phi_f from the cell densities rho (upwind by the sign of G_f, or all upward), the
// donors, and with kDerivatives d phi_f / d N of the (up to) three cells (flux_jacobian). Upward, the faces whose
// donor has neighbours on both sides (2 .. n - 1) are one vector loop without tests; the others (nothing through the
// bottom face, first order next to the ends) go through their stencil, or, upward without derivatives, take the
// donor's density directly (what their stencil gives).
template <class T, Limiter L, bool kUpward, bool kDerivatives>
void FvGrowth::face_densities(const T* rho, const T* G, T* phi, int* donor, FaceDerivatives* dphi) const {
  const int n = n_, nf = n_ + 1;
  auto one = [&](int f) {
    const Stencil s = stencil(f, kUpward || !(G[f] < 0.0));
    donor[f] = s.donor;
    double da = 0.0, db = 0.0;
    if (s.donor < 0)
      phi[f] = T(0.0);
    else if (!s.full)
      phi[f] = rho[s.donor];
    else
      phi[f] = face_density<L, kDerivatives>(rho[s.donor], rho[s.down], rho[s.up], s.cd, s.cu, da, db);
    if constexpr (kDerivatives) dphi[f] = derivatives(s, da, db);
  };
  const int lo = kUpward ? std::min(2, nf) : nf, hi = kUpward ? std::max(lo, n) : nf;
  if constexpr (kUpward && !kDerivatives) {  // faces 0, 1 and n: none through the bottom, first order at the ends
    phi[0] = T(0.0), donor[0] = -1;
    for (int f = 1; f < lo; ++f) phi[f] = rho[f - 1], donor[f] = f - 1;
  } else {
    for (int f = 0; f < lo; ++f) one(f);
  }
  if constexpr (kUpward) {
    const double *cp = cplus_.data(), *cm = cminus_.data();
    for (int f = lo; f < hi; ++f) donor[f] = f - 1;
    for (int f = lo; f < hi; ++f) {  // the vector loop
      double da, db;
      phi[f] = face_density<L, kDerivatives>(rho[f - 1], rho[f], rho[f - 2], cp[f - 1], cm[f - 1], da, db);
      if constexpr (kDerivatives) dphi[f] = derivatives(stencil(f, true), da, db);
    }
  }
  for (int f = hi; f < nf; ++f) {
    if constexpr (kUpward && !kDerivatives)
      phi[f] = rho[f - 1], donor[f] = f - 1;
    else
      one(f);
  }
}

// phi = nd + sigma(a, b)/2, a = (n_down - nd) cd, b = (nd - n_up) cu, n_k = N_k / w_k
FvGrowth::FaceDerivatives FvGrowth::derivatives(const Stencil& s, double da, double db) const {
  FaceDerivatives r{{-1, -1, -1}, {0.0, 0.0, 0.0}};
  if (s.donor < 0) return r;
  r.cols[0] = s.donor;
  r.d[0] = 1.0 / width_[s.donor];
  if (!s.full) return r;
  r.cols[1] = s.down, r.cols[2] = s.up;
  r.d[0] += 0.5 * (-da * s.cd + db * s.cu) / width_[s.donor];
  r.d[1] = 0.5 * da * s.cd / width_[s.down];
  r.d[2] = -0.5 * db * s.cu / width_[s.up];
  return r;
}

template <class T>
void FvGrowth::term_scales(const GrowthTerms<T>& g, const T* phi, TermScale<T>* ts) const {
  const int nf = n_ + 1;
  for (int k = 0; k < g.terms; ++k) {
    ts[k] = {T(g.amount[k]), T(0.0), true};
    if (!g.normalized) continue;
    const T* s = g.shape + size_t(k) * nf;
    T integral(0.0);
    for (int f = 0; f < nf; ++f) integral += s[f] * phi[f] * dx_face_[f];
    if (!(integral > 0.0)) {  // no particles to grow on
      ts[k] = {T(0.0), T(0.0), false};
      continue;
    }
    ts[k].inv = 1.0 / integral;
    ts[k].value = g.amount[k] * ts[k].inv;
  }
}

// G(d_f) = sum over the growing terms of scale_k s_k(d_f), added in the terms' order: term by term over the faces.
template <class T>
void FvGrowth::growth_rates(const GrowthTerms<T>& g, const TermScale<T>* ts, T* G) const {
  const int nf = n_ + 1;
  std::fill(G, G + nf, T(0.0));
  for (int k = 0; k < g.terms; ++k) {
    if (!ts[k].grows) continue;
    const T v = ts[k].value, *s = g.shape + size_t(k) * nf;
    for (int f = 0; f < nf; ++f) G[f] += v * s[f];
  }
}

// The scheme, for doubles and Jets and every limiter: the cell densities, the face densities (into F) and the growth
// rates G (normalized laws: from the face densities; absolute laws: first, as they pick the upwind side), then
// F = G phi. With `jac` (doubles), also what flux_jacobian reads: the face densities, their derivatives and 1 / I_k.
template <class T, Limiter L>
T FvGrowth::flux_values(const T* N, const GrowthTerms<T>& g, T* F, int* donor, std::vector<T>& G,
                        JacobianParts* jac) const {
  const int n = n_, nf = n_ + 1;
  thread_local std::vector<T> rho;
  rho.resize(n), G.resize(nf);
  for (int k = 0; k < n; ++k) rho[k] = N[k] / width_[k];
  constexpr int kTerms = 4;  // the terms' scales of up to this many on the stack
  TermScale<T> stack[kTerms];
  std::vector<TermScale<T>> heap(g.terms > kTerms ? g.terms : 0);
  TermScale<T>* ts = g.terms > kTerms ? heap.data() : stack;
  FaceDerivatives* d = nullptr;
  if (jac) jac->dphi.resize(nf), d = jac->dphi.data();
  auto faces = [&](auto upward) {
    if (d)
      face_densities<T, L, decltype(upward)::value, true>(rho.data(), G.data(), F, donor, d);
    else
      face_densities<T, L, decltype(upward)::value, false>(rho.data(), G.data(), F, donor, d);
  };
  if (g.normalized) {  // volume-normalized laws grow (a_k >= 0, s_k >= 0): upwind from below
    faces(std::true_type{});
    term_scales(g, F, ts);
    growth_rates(g, ts, G.data());
  } else {
    term_scales(g, static_cast<const T*>(nullptr), ts);  // absolute laws read no face density
    growth_rates(g, ts, G.data());
    faces(std::false_type{});
  }
  if constexpr (std::is_same_v<T, double>) {
    if (jac) {
      jac->phi.assign(F, F + nf);
      jac->inv.resize(g.terms);
      for (int k = 0; k < g.terms; ++k) jac->inv[k] = ts[k].inv;
    }
  }
  for (int f = 0; f < nf; ++f) F[f] = G[f] * F[f];
  T W(0.0);
  for (int f = 0; f < nf; ++f) W += F[f] * dx_face_[f];
  return W;
}

double FvGrowth::fluxes(const double* N, const GrowthTerms<double>& g, double* F, int* donor) const {
  thread_local std::vector<double> G;
  return with_limiter(limiter_, [&](auto L) { return flux_values<double, L.value>(N, g, F, donor, G, nullptr); });
}
Jet FvGrowth::fluxes(const Jet* N, const GrowthTerms<Jet>& g, Jet* F, int* donor) const {
  thread_local std::vector<Jet> G;
  return with_limiter(limiter_, [&](auto L) { return flux_values<Jet, L.value>(N, g, F, donor, G, nullptr); });
}

void FvGrowth::flux_jacobian(const double* N, const GrowthTerms<double>& g, double* dF) const {
  const int n = n_, nf = n_ + 1;
  JacobianParts x;
  std::vector<double> G, F(nf);
  std::vector<int> donor(nf);
  with_limiter(limiter_, [&](auto L) { flux_values<double, L.value>(N, g, F.data(), donor.data(), G, &x); });
  const std::vector<FaceDerivatives>& fc = x.dphi;
  // dF_f/dN_l = G_f dphi_f/dN_l + phi_f dG_f/dN_l; the second term only for normalized laws, where
  // dG_f/dN_l = -sum_k a_k s_kf / I_k^2 dI_k/dN_l and dI_k/dN_l = sum_f' s_kf' dx_f' dphi_f'/dN_l.
  std::fill(dF, dF + size_t(nf) * n, 0.0);
  for (int f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c)
      if (fc[f].cols[c] >= 0) dF[size_t(f) * n + fc[f].cols[c]] += G[f] * fc[f].d[c];
  if (g.normalized) {
    std::vector<double> dI(n);
    for (int k = 0; k < g.terms; ++k) {
      if (x.inv[k] == 0.0) continue;
      const double* s = g.shape + size_t(k) * nf;
      std::fill(dI.begin(), dI.end(), 0.0);
      for (int f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c)
          if (fc[f].cols[c] >= 0) dI[fc[f].cols[c]] += s[f] * dx_face_[f] * fc[f].d[c];
      const double coef = -g.amount[k] * x.inv[k] * x.inv[k];
      for (int f = 0; f < nf; ++f) {
        const double w = coef * s[f] * x.phi[f];
        if (w == 0.0) continue;
        double* row = &dF[size_t(f) * n];
        for (int l = 0; l < n; ++l) row[l] += w * dI[l];
      }
    }
  }
}

}  // namespace granuflow::kernels
