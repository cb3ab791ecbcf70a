// Numerical schemes for aggregation: they turn a kernel matrix beta (aggregation/aggregation_kernel.hpp) and
// the class numbers N into rates dN/dt on a Grid, conserving in the discrete equations
//     number:  sum_i dN_i/dt + d(number_above)/dt = -1/2 sum_{j,k} beta_jk N_j N_k   (one particle per event)
//     volume:  sum_i x_i dN_i/dt + d(volume_above)/dt = 0
// (paper 001, Eqs. (21), (24); docs/verification.md "Conservation"). Two schemes are registered: fixed_pivot
// (Kumar & Ramkrishna 1996) and cell_average (Kumar et al. 2006).
//
// Contract: rates are added to out[0, n + kOutsideRows) (redistribution.hpp); the Jacobian d out / dN is added
// to J, row-major with n columns. beta is row-major n x n and symmetric. setup() is called once per grid.
#pragma once
#include <string>
#include <type_traits>
#include <vector>

#include "discretization/grid.hpp"
#include "discretization/redistribution.hpp"
#include "granuflow/ad.hpp"

namespace granuflow::kernels {

class AggregationScheme {
 public:
  virtual ~AggregationScheme() = default;
  virtual void setup(const Grid& g) = 0;
  virtual void add_rates(const double* N, const double* beta, double* out) const = 0;
  virtual void add_rates(const Jet* N, const Jet* beta, Jet* out) const = 0;
  virtual void add_jacobian(const double* N, const double* beta, double* J) const = 0;
};

template <class Derived>
class AggregationSchemeT : public AggregationScheme {
 public:
  void add_rates(const double* N, const double* beta, double* out) const override {
    static_cast<const Derived&>(*this).rates(N, beta, out);
  }
  void add_rates(const Jet* N, const Jet* beta, Jet* out) const override {
    static_cast<const Derived&>(*this).rates(N, beta, out);
  }
};

// Skips empty classes in double evaluations only: with Jets a zero value may still carry a derivative.
template <class T>
bool skip_empty(const T& v) {
  if constexpr (std::is_same_v<T, double>)
    return v == 0.0;
  else
    return false;
}

// The pair loop both schemes share (paper 001, Eqs. (21), (24)): for every pair j <= k, numbered p along the
// row-major upper triangle, the event rate r = 1/2 beta_jj N_j^2 (j = k) or beta_jk N_j N_k; the partners' deaths
// are subtracted from out here and birth(p, r) places the aggregates.
template <class T, class Birth>
void for_each_event(int n, const T* N, const T* beta, T* out, Birth&& birth) {
  size_t p = 0;
  for (int j = 0; j < n; ++j) {
    if (skip_empty(N[j])) {
      p += n - j;
      continue;
    }
    const T* bj = beta + size_t(j) * n;
    T death = bj[j] * N[j] * N[j];  // the j = k pair: 1/2 beta N_j^2 events, two particles each
    birth(p++, T(0.5 * death));
    for (int k = j + 1; k < n; ++k, ++p) {
      const T r = bj[k] * N[j] * N[k];
      death += r;
      out[k] -= r;
      birth(p, r);
    }
    out[j] -= death;
  }
}

// Derivative of for_each_event with respect to N (J row-major, n columns): the deaths' part is added to J here;
// birth(p, j, k, dr/dN_j, dr/dN_k) places the births' part (for j = k only dr/dN_j = beta N_j, and dr/dN_k = 0).
template <class Birth>
void for_each_event_jacobian(int n, const double* N, const double* beta, double* J, Birth&& birth) {
  size_t p = 0;
  for (int j = 0; j < n; ++j) {
    const double* bj = beta + size_t(j) * n;
    const double djj = bj[j] * N[j];  // r = 1/2 beta N_j^2: dr/dN_j = beta N_j; class j loses 2 r
    J[size_t(j) * n + j] -= 2.0 * djj;
    birth(p++, j, j, djj, 0.0);
    for (int k = j + 1; k < n; ++k, ++p) {
      const double dj = bj[k] * N[k], dk = bj[k] * N[j];  // dr/dN_j, dr/dN_k of r = beta N_j N_k
      J[size_t(j) * n + j] -= dj;
      J[size_t(j) * n + k] -= dk;
      J[size_t(k) * n + j] -= dj;
      J[size_t(k) * n + k] -= dk;
      birth(p, j, k, dj, dk);
    }
  }
}

}  // namespace granuflow::kernels
