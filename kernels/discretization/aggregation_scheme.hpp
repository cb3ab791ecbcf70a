// Numerical schemes for aggregation: they turn a kernel matrix beta (aggregation/aggregation_kernel.hpp) and
// the class numbers N into rates dN/dt on a Grid, conserving in the discrete equations
//     number:  sum_i dN_i/dt + d(number_above)/dt = -1/2 sum_{j,k} beta_jk N_j N_k   (one particle per event)
//     volume:  sum_i x_i dN_i/dt + d(volume_above)/dt = 0
// (paper 001, Eqs. (21), (24); VERIFY.md "Conservation"). Two schemes are registered: fixed_pivot
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
  if constexpr (std::is_same_v<T, double>) return v == 0.0;
  else return false;
}

}  // namespace granuflow::kernels
