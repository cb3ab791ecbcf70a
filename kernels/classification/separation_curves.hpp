// Separation curves (separation_curve.hpp gives the contract), each with its cut size d_cut (T(d_cut) = 1/2):
//  * sharp: the ideal screen, T = 0 below d_cut and 1 above; the cell holding d_cut splits by its share of ln d
//    above d_cut (exact cell average);
//  * plitt: T(d) = 1 - exp(-ln 2 (d / d_cut)^m), Plitt (1976); m -> infinity is the sharp cut;
//  * molerus_hoffmann: T(d) = 1 / (1 + (d_cut / d)^2 exp(k (1 - (d / d_cut)^2))), Molerus & Hoffmann (1969); larger k
//    is sharper.
#pragma once
#include <cmath>

#include "classification/separation_curve.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

inline ParamSpec cut_size_param() {
  return {"d_cut", "m", 1e-3, 1e-7, 1.0, "cut size, T(d_cut) = 1/2", "operating input"};
}

class SharpCut : public SeparationCurveT<SharpCut> {
 public:
  std::vector<ParamSpec> params() const override { return {cut_size_param()}; }
  template <class T>
  T coarse(double d, const T* p) const {
    return T(d > p[0] ? 1.0 : (d < p[0] ? 0.0 : 0.5));
  }
  // Exact: the fraction of [ln lo, ln hi] above ln d_cut.
  template <class T>
  T cell_average_t(double lo, double hi, const T* p) const {
    using std::log;
    if (!(p[0] > lo)) return T(1.0);
    if (!(p[0] < hi)) return T(0.0);
    return (std::log(hi) - log(p[0])) / std::log(hi / lo);
  }
};

class PlittCurve : public SeparationCurveT<PlittCurve> {
 public:
  std::vector<ParamSpec> params() const override {
    return {cut_size_param(), {"m", "-", 5.0, 0.5, 100.0, "sharpness (larger: sharper)", "Plitt (1976)"}};
  }
  template <class T>
  T coarse(double d, const T* p) const {
    using std::exp, std::pow;
    return 1.0 - exp(-std::log(2.0) * pow(T(d / p[0]), p[1]));
  }
};

class MolerusHoffmannCurve : public SeparationCurveT<MolerusHoffmannCurve> {
 public:
  std::vector<ParamSpec> params() const override {
    return {cut_size_param(), {"k", "-", 5.0, 0.1, 100.0, "sharpness (larger: sharper)", "Molerus & Hoffmann (1969)"}};
  }
  template <class T>
  T coarse(double d, const T* p) const {
    using std::exp;
    const T r = d / p[0];
    const T e = p[1] * (1.0 - r * r);
    // written with the exponent bounded so that far from the cut T saturates at 0 or 1 instead of overflowing
    if (e > 700.0) return T(0.0);
    return 1.0 / (1.0 + exp(e) / (r * r));
  }
};

void register_separation_curves(Registry<SeparationCurve>& r);

}  // namespace granuflow::kernels
