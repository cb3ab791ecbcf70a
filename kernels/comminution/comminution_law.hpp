// Comminution laws of a mill on the size grid: the mass of each feed class k leaves the mill spread over classes
// i <= k (a mill never makes particles bigger),
//     m_out,i = sum_k P_ik m_in,k,     P_ik >= 0,   sum_i P_ik = 1 exactly (mass is conserved per class),
// built once per run from two functions of the parent's pivot diameter D a law writes as templates:
//     template <class T> T broken(double D, const T* p) const;           // mass fraction of the parents that break
//     template <class T> T finer(double d, double D, const T* p) const;  // cumulative mass fraction of the fragments
//                                                                         // of a parent D finer than d (d <= D)
// Fragments between the parent's lower cell edge and D stay in the parent's class, fragments below the grid go to
// the first class, and the diagonal is the remainder 1 - sum_{i<k} P_ik, so every column sums to one to round-off
// whatever the law.
#pragma once
#include <vector>

#include "kernel_base.hpp"

namespace granuflow::kernels {

class ComminutionLaw : public KernelBase {
 public:
  // P (n x n, column-major: P[k * n + i] from parent class k to class i) for the n + 1 diameter edges `de` and the n
  // pivot diameters `dp` (m).
  virtual void matrix(const std::vector<double>& de, const std::vector<double>& dp, const double* p,
                      double* P) const = 0;
  virtual void matrix(const std::vector<double>& de, const std::vector<double>& dp, const Jet* p, Jet* P) const = 0;
  // True when the fragments' size distribution is the same for every parent (finer(d, D) independent of D, broken(D)
  // constant): then P_ik = P_i,k' for all i < k < k' as built, and a mill applies P in O(n) with a suffix sum,
  // out_i = P_ii in_i + P_i,n-1 sum_{k > i} in_k, instead of an O(n^2) product.
  virtual bool parent_independent() const { return false; }
};

template <class Derived>
class ComminutionLawT : public ComminutionLaw {
 public:
  void matrix(const std::vector<double>& de, const std::vector<double>& dp, const double* p, double* P) const override {
    fill(de, dp, p, P);
  }
  void matrix(const std::vector<double>& de, const std::vector<double>& dp, const Jet* p, Jet* P) const override {
    fill(de, dp, p, P);
  }

 private:
  template <class T>
  void fill(const std::vector<double>& de, const std::vector<double>& dp, const T* p, T* P) const {
    const Derived& law = static_cast<const Derived&>(*this);
    const int n = static_cast<int>(dp.size());
    for (int k = 0; k < n; ++k) {
      T* col = P + size_t(k) * n;
      const T s = law.broken(dp[k], p);
      T below(0.0), placed(0.0);
      for (int i = 0; i < k; ++i) {
        const T upto = law.finer(de[i + 1], dp[k], p);
        col[i] = s * (upto - below);  // class 0 also takes the fragments below the grid
        below = upto;
        placed += col[i];
      }
      col[k] = 1.0 - placed;
      for (int i = k + 1; i < n; ++i) col[i] = T(0.0);
    }
  }
};

}  // namespace granuflow::kernels
