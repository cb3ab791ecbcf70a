// Growth laws G(d) = dd/dt, m/s, of layering (paper 003, Eqs. (7.32)-(7.36)), evaluated at the cell faces of
// the size grid. A law is a sum of terms G(d) = sum_k a_k s_k(d):
//   * absolute laws: a_k in m/s (a prescribed growth rate);
//   * volume-normalized laws (paper 003, Eqs. (7.33), (7.35)): a_k is the volume growth rate in m^3/s that
//     term k must deliver (e.g. M_sus / rho_s), and the scheme divides by the population's integral
//     int (pi/2) d^2 s_k(d) n(d) dd evaluated with the scheme's own fluxes, so the discrete mass growth rate
//     equals sum_k a_k to round-off ("mass growth rate exact").
#pragma once
#include "kernel_base.hpp"

namespace granuflow::kernels {

class GrowthLaw : public KernelBase {
 public:
  virtual int terms() const { return 1; }
  virtual bool volume_normalized() const = 0;
  // shape[k * nf + f] = s_k(d[f]) (-), amount[k] = a_k, for nf face diameters d (m).
  virtual void evaluate(const double* d, int nf, const double* p, double* shape, double* amount) const = 0;
  virtual void evaluate(const double* d, int nf, const Jet* p, Jet* shape, Jet* amount) const = 0;
};

template <class Derived>
class GrowthLawT : public GrowthLaw {
 public:
  void evaluate(const double* d, int nf, const double* p, double* s, double* a) const override {
    static_cast<const Derived&>(*this).eval(d, nf, p, s, a);
  }
  void evaluate(const double* d, int nf, const Jet* p, Jet* s, Jet* a) const override {
    static_cast<const Derived&>(*this).eval(d, nf, p, s, a);
  }
};

}  // namespace granuflow::kernels
