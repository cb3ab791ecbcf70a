// Normalized drying curves v(eta): the drying rate of a class over its rate in the constant-rate period, as a function
// of the normalized moisture eta = (X - X_eq) / (X_cr - X_eq) (paper 000, section 5.4.1; paper 001, Eqs. (79)-(80)).
// Every curve satisfies v(0) = 0 and v(1) = 1 and is 1 in the constant-rate period eta >= 1, so a unit may apply it to
// min(eta, 1) (what the linear curve of paper 001 returns) and get the same rate as from eta itself.
//
// Below equilibrium (eta < 0: re-adsorption, which paper 001's regularized Eq. (80) allows down to eta_min) the
// review's curves are not defined and the gamma form has a pole at eta = -1 / (gamma - 1); every curve continues there
// as its tangent at 0, v = v'(0) eta, the linear re-adsorption of paper 001 with the curve's initial slope.
//
// A curve writes once, as templates on the scalar type (double for residuals, Jet for Jacobians and sensitivities),
//     template <class T> T value(const T& eta, const T* p) const;   // 0 <= eta <= 1
//     template <class T> T slope(const T* p) const;                 // v'(0)
// with p its parameters in the order of params(). The owning unit declares them with a prefix ("drying_") and hands
// their values back.
#pragma once
#include "kernel_base.hpp"

namespace granuflow::kernels {

class DryingCurve : public KernelBase {
 public:
  // v[i] = curve(eta[i]) for n classes; eta and v may be the same array.
  virtual void apply(const double* eta, int n, const double* p, double* v) const = 0;
  virtual void apply(const Jet* eta, int n, const Jet* p, Jet* v) const = 0;
  // True for the linear curve v = eta: a unit then keeps paper 001's Eq. (79) as it is and applies nothing.
  virtual bool identity() const { return false; }
  ClassNeeds needs() const override {  // a class's moisture, through eta
    ClassNeeds n;
    n.moisture = true;
    return n;
  }
};

template <class Derived>
class DryingCurveT : public DryingCurve {
 public:
  void apply(const double* eta, int n, const double* p, double* v) const override { fill(eta, n, p, v); }
  void apply(const Jet* eta, int n, const Jet* p, Jet* v) const override { fill(eta, n, p, v); }

 private:
  template <class T>
  void fill(const T* eta, int n, const T* p, T* v) const {
    const Derived& d = static_cast<const Derived&>(*this);
    for (int i = 0; i < n; ++i)
      v[i] = eta[i] >= 1.0 ? T(1.0) : eta[i] >= 0.0 ? d.value(eta[i], p) : T(d.slope(p) * eta[i]);
  }
};

}  // namespace granuflow::kernels
