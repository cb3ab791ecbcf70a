// Aggregation kernels beta(u, v): the rate coefficient of one pair of particles, in 1/s per pair for absolute
// particle numbers (the birth of class k is 1/2 sum_{i,j} beta_ij N_i N_j over pairs landing in k, paper 001
// Eqs. (21), (24)). The numerical scheme that turns beta into rates lives in the population engine
// (kernels/population/population.hpp).
//
// Every kernel has the form
//     beta_ij = K_ij * E(phi_i, phi_j)
// with K from the sizes and parameters only (evaluated once per run, and again only when a parameter value
// changes) and an efficiency E of small per-class feature vectors phi_i computed from the class's fields
// (moisture, temperature, wetted fraction ...). This is what keeps state-dependent kernels cheap: phi costs O(n)
// per residual, E is a few products per pair, and the exact Jacobian needs one small forward-AD evaluation per
// class (dphi/dfields) and per pair (dE/dphi), never a hand derivation.
//
// A kernel derives from PairKernel<Derived> and writes once, as templates on the scalar type,
//     template <class T> T factor(const ClassState<T>& s, int i, int j, const T* p) const;           // K_ij, i <= j
// and, if it reads fields (kFeatures > 0),
//     static constexpr int kFeatures = m;                                                              // m <= 4
//     template <class T> void features(const ClassState<T>& s, int i, const T* p, T* phi) const;      // phi_i
//     template <class T> T efficiency(const T* phi_i, const T* phi_j, const T* p) const;              // symmetric
#pragma once
#include <algorithm>
#include <memory>
#include <type_traits>
#include <vector>

#include "kernel_base.hpp"

namespace granuflow::kernels {

inline constexpr int kMaxFeatures = kAdChunk / 2;  // E's derivative takes one Jet per pair: 2 m directions
inline constexpr int kMaxEfficiencyTerms = 4;      // terms of a factored efficiency (efficiency_terms)
inline constexpr int kMaxFactorTerms = 4;          // terms of a separable size factor (factor_terms)

class AggregationKernel : public KernelBase {
 public:
  // K[i * n + j] for all classes (row-major, symmetric), 1/s.
  virtual void factor(const ClassState<double>& s, const double* p, double* K) const = 0;
  virtual void factor(const ClassState<Jet>& s, const Jet* p, Jet* K) const = 0;
  // K as a short sum of separable terms, K_ij = sum_t a[t * n + i] b[t * n + j] for every pair, exactly (not an
  // approximation): fills a and b (kMaxFactorTerms x n each) and returns the number of terms, or 0 when K has no such
  // form. The engine then sums the aggregation of a size-only kernel with prefix sums, O(n) per term instead of
  // O(n^2) per right-hand side (population.cpp, aggregate_separable).
  virtual int factor_terms(const ClassState<double>& /*s*/, const double* /*p*/, double* /*a*/, double* /*b*/) const {
    return 0;
  }
  // Number of features per class; 0: beta = K.
  virtual int n_features() const { return 0; }
  // phi[i * m + k] for every class.
  virtual void features(const ClassState<double>& /*s*/, const double* /*p*/, double* /*phi*/) const {}
  virtual void features(const ClassState<Jet>& /*s*/, const Jet* /*p*/, Jet* /*phi*/) const {}
  virtual double efficiency(const double* /*phi_i*/, const double* /*phi_j*/, const double* /*p*/) const { return 1.0; }
  virtual Jet efficiency(const Jet* /*phi_i*/, const Jet* /*phi_j*/, const Jet* /*p*/) const { return Jet(1.0); }
  // E for every pair i <= j of n classes, in row-major upper-triangle order (one call per residual).
  virtual void efficiencies(const double* phi, int n, const double* p, double* E) const = 0;
  virtual void efficiencies(const Jet* phi, int n, const Jet* p, Jet* E) const = 0;
  // E and its derivatives by the partners' features for every pair, in the same order, for the engine's analytic
  // Jacobian: dEa[q * m + c] = dE/dphi_i[c], dEb[q * m + c] = dE/dphi_j[c] (m = n_features(), p the kernel's np
  // parameters). One call per Jacobian, forward AD with 2 m directions per pair.
  virtual void efficiency_gradients(const double* phi, int n, const double* p, int np, double* E, double* dEa,
                                    double* dEb) const = 0;
  // The efficiency as a short sum of products, E(phi_i, phi_j) = sum_t sign_t h_t(phi_i) h_t(phi_j) for every pair,
  // exactly: fills h[t * n + i] for n classes and sign[t] (+1 or -1) and returns the number of terms (at most
  // kMaxEfficiencyTerms), or 0 when E has no such form. The 2-D population (population/population2d.hpp) then
  // evaluates aggregation as a few convolutions instead of a loop over every pair of classes. Kernels without
  // features have E = 1: one term, h = 1.
  virtual int efficiency_terms(const double* /*phi*/, int n, const double* /*p*/, double* h, double* sign) const {
    if (n_features() > 0) return 0;
    for (int i = 0; i < n; ++i) h[i] = 1.0;
    sign[0] = 1.0;
    return 1;
  }
  // beta = K E for all pairs, row-major n x n (for tests and tools; the engine uses the parts).
  void beta(const ClassState<double>& s, const double* p, double* out) const {
    factor(s, p, out);
    const int m = n_features();
    if (m == 0) return;
    std::vector<double> phi(size_t(s.n) * m);
    features(s, p, phi.data());
    for (int i = 0; i < s.n; ++i)
      for (int j = 0; j < s.n; ++j) out[size_t(i) * s.n + j] *= efficiency(&phi[size_t(i) * m], &phi[size_t(j) * m], p);
  }
};

namespace detail {
template <class D, class = void>
struct FeatureCount {
  static constexpr int value = 0;
};
template <class D>
struct FeatureCount<D, std::void_t<decltype(D::kFeatures)>> {
  static constexpr int value = D::kFeatures;
};
}  // namespace detail

template <class Derived>
class PairKernel : public AggregationKernel {
 public:
  void factor(const ClassState<double>& s, const double* p, double* K) const override { fill(s, p, K); }
  void factor(const ClassState<Jet>& s, const Jet* p, Jet* K) const override { fill(s, p, K); }
  // Derived is complete only inside member functions (CRTP), so its feature count is read there.
  int n_features() const override { return features_of<Derived>(); }
  void features(const ClassState<double>& s, const double* p, double* phi) const override { feat(s, p, phi); }
  void features(const ClassState<Jet>& s, const Jet* p, Jet* phi) const override { feat(s, p, phi); }
  double efficiency(const double* a, const double* b, const double* p) const override { return eff(a, b, p); }
  Jet efficiency(const Jet* a, const Jet* b, const Jet* p) const override { return eff(a, b, p); }
  void efficiencies(const double* phi, int n, const double* p, double* E) const override { all(phi, n, p, E); }
  void efficiencies(const Jet* phi, int n, const Jet* p, Jet* E) const override { all(phi, n, p, E); }
  void efficiency_gradients(const double* phi, int n, const double* p, int np, double* E, double* dEa,
                            double* dEb) const override {
    constexpr int m = features_of<Derived>();
    const size_t pairs = size_t(n) * (n + 1) / 2;
    if constexpr (m == 0) {
      std::fill(E, E + pairs, 1.0);
    } else {
      using Dual = ceres::Jet<double, 2 * m>;  // the directions of both partners' features, no more
      std::vector<Dual> pd(p, p + np);
      Dual a[m], b[m];
      size_t q = 0;
      for (int i = 0; i < n; ++i)
        for (int j = i; j < n; ++j, ++q) {
          for (int c = 0; c < m; ++c) {
            a[c] = Dual(phi[size_t(i) * m + c]), a[c].v[c] = 1.0;
            b[c] = Dual(phi[size_t(j) * m + c]), b[c].v[m + c] = 1.0;
          }
          const Dual e = self().efficiency(a, b, pd.data());
          E[q] = e.a;
          for (int c = 0; c < m; ++c) dEa[q * m + c] = e.v[c], dEb[q * m + c] = e.v[m + c];
        }
    }
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
  template <class T>
  void fill(const ClassState<T>& s, const T* p, T* K) const {
    for (int i = 0; i < s.n; ++i)
      for (int j = i; j < s.n; ++j) K[size_t(i) * s.n + j] = K[size_t(j) * s.n + i] = self().factor(s, i, j, p);
  }
  template <class D>
  static constexpr int features_of() {
    constexpr int m = detail::FeatureCount<D>::value;
    static_assert(m <= kMaxFeatures, "an aggregation kernel has at most kMaxFeatures features per class");
    return m;
  }
  // A class's features depend on that class alone: in doubles the loop is a vector loop where the kernel's
  // closures allow.
  template <class T>
  void feat(const ClassState<T>& s, const T* p, T* phi) const {
    constexpr int m = features_of<Derived>();
    const int n = s.n;
    if constexpr (m > 0 && std::is_same_v<T, double>) {
#pragma omp simd
      for (int i = 0; i < n; ++i) self().features(s, i, p, phi + size_t(i) * m);
    } else if constexpr (m > 0) {
      for (int i = 0; i < n; ++i) self().features(s, i, p, phi + size_t(i) * m);
    }
  }
  template <class T>
  void all(const T* phi, int n, const T* p, T* E) const {
    constexpr int m = features_of<Derived>();
    size_t q = 0;
    for (int i = 0; i < n; ++i)
      for (int j = i; j < n; ++j, ++q) E[q] = eff(phi + size_t(i) * m, phi + size_t(j) * m, p);
  }
  template <class T>
  T eff(const T* a, const T* b, const T* p) const {
    if constexpr (features_of<Derived>() > 0)
      return self().efficiency(a, b, p);
    else
      return T(1.0);
  }
};

}  // namespace granuflow::kernels
