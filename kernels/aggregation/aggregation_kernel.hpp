// Aggregation kernels beta(u, v): the rate coefficient of one pair of particles, in 1/s per pair for absolute
// particle numbers (the birth of class k is 1/2 sum_{i,j} beta_ij N_i N_j over pairs landing in k, paper 001
// Eqs. (21), (24)). The numerical scheme that turns beta into rates lives in kernels/discretization/.
//
// A pairwise kernel derives from PairKernel<Derived> and writes once
//     template <class T> T pair(const ClassState<T>& s, int i, int j, const T* p) const;
// evaluated for i <= j and mirrored, so beta is symmetric by construction.
#pragma once
#include <memory>

#include "kernel_base.hpp"

namespace granuflow::kernels {

class AggregationKernel : public KernelBase {
 public:
  // beta[i * n + j] for all classes (row-major, symmetric), 1/s.
  virtual void evaluate(const ClassState<double>& s, const double* p, double* beta) const = 0;
  virtual void evaluate(const ClassState<Jet>& s, const Jet* p, Jet* beta) const = 0;
};

template <class Derived>
class PairKernel : public AggregationKernel {
 public:
  void evaluate(const ClassState<double>& s, const double* p, double* beta) const override { fill(s, p, beta); }
  void evaluate(const ClassState<Jet>& s, const Jet* p, Jet* beta) const override { fill(s, p, beta); }

 private:
  template <class T>
  void fill(const ClassState<T>& s, const T* p, T* beta) const {
    const auto& self = static_cast<const Derived&>(*this);
    for (int i = 0; i < s.n; ++i)
      for (int j = i; j < s.n; ++j) beta[size_t(i) * s.n + j] = beta[size_t(j) * s.n + i] = self.pair(s, i, j, p);
  }
};

}  // namespace granuflow::kernels
