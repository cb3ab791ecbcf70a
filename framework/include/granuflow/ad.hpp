// Forward automatic differentiation: residuals are templates on the scalar type and are instantiated for
// double and for Jet (Ceres' dual number with kAdChunk derivative slots). Jacobian columns and sensitivity
// directions are evaluated kAdChunk at a time.
#pragma once
#include <ceres/jet.h>

#include <type_traits>

namespace granuflow {

inline constexpr int kAdChunk = 8;
using Jet = ceres::Jet<double, kAdChunk>;

inline double value_of(double x) { return x; }
template <int N>
double value_of(const ceres::Jet<double, N>& x) {
  return x.a;
}

// A value that is exactly zero and carries nothing: a double 0. A Jet is never "empty" (a zero value may still carry a
// derivative), so loops that skip empty classes skip them in double evaluations only.
inline bool is_empty(double v) { return v == 0.0; }
template <int N>
bool is_empty(const ceres::Jet<double, N>&) {
  return false;
}

// The one of two work objects that belongs to scalar type T (d for double evaluations, j for Jet ones): units and
// the engine keep separate work arrays per scalar type so that an AD sweep never overwrites a residual's.
template <class T, class D, class J>
auto& per_scalar(D& d, J& j) {
  if constexpr (std::is_same_v<T, double>)
    return d;
  else
    return j;
}

}  // namespace granuflow
