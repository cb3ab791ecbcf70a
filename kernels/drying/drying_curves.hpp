// The normalized drying curves of paper 000, section 5.4.1 (drying_curve.hpp gives the contract):
//  * linear: v = eta, Peglow et al.'s curve and paper 001's Eq. (79);
//  * cubic: v = A eta + B eta^2 + C eta^3 with A + B + C = 1 (so that v(1) = 1), three fitted coefficients;
//  * gamma: v = gamma eta / (1 + (gamma - 1) eta), one fitted parameter; gamma = 1 is the linear curve, gamma > 1
//    dries faster in the falling-rate period (the curve bends above the diagonal), gamma < 1 slower.
#pragma once
#include <string>
#include <vector>

#include "drying/drying_curve.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class LinearDryingCurve : public DryingCurveT<LinearDryingCurve> {
 public:
  bool identity() const override { return true; }
  template <class T>
  T value(const T& eta, const T*) const {
    return eta;  // paper 000, section 5.4.1 (v = eta); paper 001, Eq. (79)
  }
  template <class T>
  T slope(const T*) const {
    return T(1.0);
  }
};

class CubicDryingCurve : public DryingCurveT<CubicDryingCurve> {
 public:
  std::vector<ParamSpec> params() const override;
  void check(const ClassState<double>& s, const double* p, const std::string& where) const override;
  template <class T>
  T value(const T& eta, const T* p) const {
    return ((p[2] * eta + p[1]) * eta + p[0]) * eta;  // paper 000, section 5.4.1: A X + B X^2 + C X^3
  }
  template <class T>
  T slope(const T* p) const {
    return p[0];
  }
};

class GammaDryingCurve : public DryingCurveT<GammaDryingCurve> {
 public:
  std::vector<ParamSpec> params() const override;
  template <class T>
  T value(const T& eta, const T* p) const {
    return p[0] * eta / (1.0 + (p[0] - 1.0) * eta);  // paper 000, section 5.4.1: gamma X / (1 + (gamma - 1) X)
  }
  template <class T>
  T slope(const T* p) const {
    return p[0];
  }
};

// The cubic's rule A + B + C = 1 to this tolerance (a user types three rounded coefficients).
inline constexpr double kCubicSumTolerance = 1e-9;

void register_drying_curves(Registry<DryingCurve>& r);

}  // namespace granuflow::kernels
