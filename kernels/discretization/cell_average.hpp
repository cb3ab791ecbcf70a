// Cell average technique (Kumar et al. 2006, Chem. Eng. Sci. 61, Eqs. (13)-(17)) for aggregation: the births
// landing in each cell are first summed as a packet (number B_i, volume V_i); each packet is then split
// between the pivot of its cell and the neighbouring pivot on the side of its mean volume V_i / B_i, keeping
// number and volume. Unlike the fixed pivot, the split follows the actual mean of the new particles, which
// makes the scheme accurate for the large classes (less over-prediction of the second moment).
#pragma once
#include "discretization/aggregation_scheme.hpp"

namespace granuflow::kernels {

class CellAverageAggregation : public AggregationSchemeT<CellAverageAggregation> {
 public:
  void setup(const Grid& g) override;
  void add_jacobian(const double* N, const double* beta, double* J) const override;

  template <class T>
  void rates(const T* N, const T* beta, T* out) const {
    auto& B = scratch<T>().b;
    auto& V = scratch<T>().v;
    B.assign(n_ + 1, T(0.0));
    V.assign(n_ + 1, T(0.0));
    for_each_event(n_, N, beta, out, [&](size_t p, const T& r) {
      B[cell_[p]] += r;
      V[cell_[p]] += vsum_[p] * r;
    });
    for (int c = 0; c < n_; ++c)
      if (!skip_empty(B[c])) split_between(*grid_, side(c, B[c], V[c]), B[c], V[c], out);
    out[n_ + kNumberAbove] += B[n_];  // aggregates beyond the top edge leave whole
    out[n_ + kVolumeAbove] += V[n_];
  }

 private:
  // Lower extended pivot of the interval the packet of cell c is split over (Kumar et al. 2006, Eq. (15)).
  template <class T>
  int side(int c, const T& b, const T& v) const {
    return v >= grid_->pivot(c) * b ? c : c - 1;
  }
  template <class T>
  struct Scratch {
    std::vector<T> b, v;
  };
  template <class T>
  Scratch<T>& scratch() const {
    if constexpr (std::is_same_v<T, double>)
      return sd_;
    else
      return sj_;
  }
  const Grid* grid_ = nullptr;
  int n_ = 0;
  std::vector<int> cell_;     // per pair j <= k: cell of x_j + x_k (n: above the grid)
  std::vector<double> vsum_;  // per pair: x_j + x_k
  mutable Scratch<double> sd_;
  mutable Scratch<Jet> sj_;
  mutable std::vector<double> db_, dv_;
};

}  // namespace granuflow::kernels
