// Separation (grade-efficiency) curves of classifiers: T(d), the fraction of the particles of diameter d that a
// screen deck, a sifter or a classifying discharge sends to its coarse side (Rumpf's Trennkurve; Plitt 1976 and
// Molerus & Hoffmann 1969 give the usual two-parameter forms: a cut size, T(d_cut) = 1/2, and a sharpness).
//
// On the size grid a class is a cell [d_lo, d_hi] whose mass is spread uniformly over ln d (the same reading the
// characteristic diameters use, discretization/psd.hpp): the class goes to the coarse side by the cell average
//     T_i = 1 / ln(d_hi / d_lo) int_{ln d_lo}^{ln d_hi} T(d) d(ln d),
// so a cut inside a cell splits that cell continuously and the split moves smoothly with d_cut (steady states and
// contour maps over a cut size have no steps). Derive from SeparationCurveT<Derived> and write once
//     template <class T> T coarse(double d, const T* p) const;                          // T(d)
// and, where a closed form of the cell average exists (the sharp cut), override cell_average_t.
#pragma once
#include <algorithm>
#include <cmath>

#include "kernel_base.hpp"

namespace granuflow::kernels {

class SeparationCurve : public KernelBase {
 public:
  // Fraction of the cell [lo, hi] (diameters, m) sent to the coarse side, 0 <= T_i <= 1.
  virtual double cell_fraction(double lo, double hi, const double* p) const = 0;
  virtual Jet cell_fraction(double lo, double hi, const Jet* p) const = 0;
  // The curve itself at diameter d (m).
  virtual double at(double d, const double* p) const = 0;
};

template <class Derived>
class SeparationCurveT : public SeparationCurve {
 public:
  double cell_fraction(double lo, double hi, const double* p) const override {
    return self().cell_average_t(lo, hi, p);
  }
  Jet cell_fraction(double lo, double hi, const Jet* p) const override { return self().cell_average_t(lo, hi, p); }
  double at(double d, const double* p) const override { return self().coarse(d, p); }

  // Gauss-Legendre (4 points) on panels no wider than 0.02 in ln d: a Plitt curve of sharpness m changes over about
  // 1/m in ln d, so the average is accurate to far below the integration tolerances for m up to about 50.
  template <class T>
  T cell_average_t(double lo, double hi, const T* p) const {
    static const double x[2] = {0.3399810435848563, 0.8611363115940526};
    static const double w[2] = {0.6521451548625461, 0.3478548451374538};
    const double la = std::log(lo), lb = std::log(hi);
    const int panels = std::max(1, static_cast<int>(std::ceil((lb - la) / 0.02)));
    const double h = (lb - la) / panels;
    T sum(0.0);
    for (int k = 0; k < panels; ++k) {
      const double mid = la + (k + 0.5) * h;
      for (int g = 0; g < 2; ++g)
        for (double s : {-1.0, 1.0})
          sum += (0.5 * w[g] / panels) * self().coarse(std::exp(mid + s * x[g] * 0.5 * h), p);
    }
    return sum;
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace granuflow::kernels
