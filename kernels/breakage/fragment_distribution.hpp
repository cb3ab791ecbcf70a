// Fragment distributions b(v|u) of breakage, given through the cumulative volume fraction
//     B(v|u) = (volume of the fragments of volume <= v) / u,   0 <= v <= u,
// so that b(v|u) = (u / v) dB/dv is the number density of fragments (paper 001, Eq. (26): b from b_cum).
// The discretization divides by B(u|u), so a law need not be normalized at the parent ("renormalized to 1 at
// the parent", docs/paper001_decisions.md), and mass is conserved to round-off whatever B is.
//
// Derive from FragmentLaw<Derived> and write once
//     template <class T> T cumulative_t(double v, double u, const T* p) const;     // B(v|u)
//     template <class T> T number_t(double a, double b, double u, const T* p) const;  // fragments in [a, b]
// number_t() may return number_by_parts(a, b, u, p) where no closed form exists.
#pragma once
#include <algorithm>
#include <cmath>

#include "kernel_base.hpp"

namespace granuflow::kernels {

class FragmentDistribution : public KernelBase {
 public:
  virtual double cumulative(double v, double u, const double* p) const = 0;
  virtual Jet cumulative(double v, double u, const Jet* p) const = 0;
  // Number of fragments with volume in [a, b] per broken parent of volume u, for 0 < a < b <= u.
  virtual double number(double a, double b, double u, const double* p) const = 0;
  virtual Jet number(double a, double b, double u, const Jet* p) const = 0;
};

template <class Derived>
class FragmentLaw : public FragmentDistribution {
 public:
  double cumulative(double v, double u, const double* p) const override { return self().cumulative_t(v, u, p); }
  Jet cumulative(double v, double u, const Jet* p) const override { return self().cumulative_t(v, u, p); }
  double number(double a, double b, double u, const double* p) const override { return self().number_t(a, b, u, p); }
  Jet number(double a, double b, double u, const Jet* p) const override { return self().number_t(a, b, u, p); }

 protected:
  // int_a^b (u/w) dB(w) = u [B(b)/b - B(a)/a] + u int_a^b B(w)/w^2 dw (by parts), the last integral by
  // 8-point Gauss-Legendre on panels of width <= 0.5 in ln w, where B is smooth (the tanh cut-off of Eq. (93) varies
  // over ln 3 in diameter, 3.3 in ln w: panels of 0.5 keep the number of fragments to 1e-12 relative).
  template <class T>
  T number_by_parts(double a, double b, double u, const T* p) const {
    static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066959342412, 0.2223810344533745, 0.1012285362903763};
    const double la = std::log(a), lb = std::log(b);
    const int panels = std::max(1, static_cast<int>(std::ceil((lb - la) / 0.5)));
    const double h = (lb - la) / panels;
    T integral(0.0);
    for (int k = 0; k < panels; ++k) {
      const double mid = la + (k + 0.5) * h;
      for (int g = 0; g < 4; ++g)
        for (double sgn : {-1.0, 1.0}) {
          const double s = mid + sgn * x[g] * 0.5 * h;
          integral += (0.5 * h * w[g] * std::exp(-s)) * self().cumulative_t(std::exp(s), u, p);
        }
    }
    return u * (self().cumulative_t(b, u, p) / b - self().cumulative_t(a, u, p) / a + integral);
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace granuflow::kernels
