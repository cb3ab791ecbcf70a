// Forward automatic differentiation: residuals are templates on the scalar type and are instantiated for
// double and for Jet (Ceres' dual number with kAdChunk derivative slots). Jacobian columns and sensitivity
// directions are evaluated kAdChunk at a time.
#pragma once
#include <ceres/jet.h>

namespace granuflow {

inline constexpr int kAdChunk = 8;
using Jet = ceres::Jet<double, kAdChunk>;

inline double value_of(double x) { return x; }
template <int N>
double value_of(const ceres::Jet<double, N>& x) {
  return x.a;
}

}  // namespace granuflow
