// Breakage selection rates S(v): the probability per unit time that one particle of a class breaks, 1/s
// (K_break of paper 001, Eqs. (23), (25)). Derive from PerClassRate<Derived> and write once
//     template <class T> T rate(const ClassState<T>& s, int i, const T* p) const;
#pragma once
#include "kernel_base.hpp"

namespace granuflow::kernels {

class SelectionRate : public KernelBase {
 public:
  virtual void evaluate(const ClassState<double>& s, const double* p, double* rate) const = 0;
  virtual void evaluate(const ClassState<Jet>& s, const Jet* p, Jet* rate) const = 0;
};

template <class Derived>
class PerClassRate : public SelectionRate {
 public:
  void evaluate(const ClassState<double>& s, const double* p, double* r) const override { fill(s, p, r); }
  void evaluate(const ClassState<Jet>& s, const Jet* p, Jet* r) const override { fill(s, p, r); }

 private:
  template <class T>
  void fill(const ClassState<T>& s, const T* p, T* r) const {
    for (int i = 0; i < s.n; ++i) r[i] = static_cast<const Derived&>(*this).rate(s, i, p);
  }
};

}  // namespace granuflow::kernels
