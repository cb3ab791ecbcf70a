// Cell average technique (Kumar et al. 2006, Chem. Eng. Sci. 61, Eqs. (13)-(17)) for aggregation: the births
// landing in each cell are first summed as a packet (number B_c, volume V_c); each packet is then split between the
// pivot of its cell and the neighbouring pivot on the side of its mean volume V_c / B_c, keeping number and volume.
// Unlike the fixed pivot, the split follows the actual mean of the new particles, which makes the scheme accurate
// for the large classes (less over-prediction of the second moment). The split is linear in (B, V) for a given side
// (redistribution.hpp), so the scheme differentiates it exactly. The sums over the pairs are those shared with the
// fixed pivot (pair_runs.hpp).
#pragma once
#include "discretization/aggregation_scheme.hpp"
#include "discretization/pair_runs.hpp"

namespace granuflow::kernels {

class CellAverageAggregation : public RunScheme<CellAverageAggregation> {
 public:
  std::string name() const override { return "cell_average"; }
  void setup(const Grid& g) override;
  void jacobian_start(Tables& t, const PopulationJacobian& J) const override;
  void jacobian_row(Tables& t, const PopulationJacobian& J, const PairEvent* events, int count) const override;
  void jacobian_finish(Tables& t, const PopulationJacobian& J) const override;
  int cell(size_t pair) const { return cell_[pair]; }  // n: beyond the top edge
  double volume(size_t pair) const { return vsum_[pair]; }
  const double* volumes() const { return vsum_.data(); }
  // For the engine's vectorized pair loop: the partners k of class j in [run_first(j), run_last(j)] (possibly empty)
  // form aggregates that stay in cell k, as the pairs with a much smaller partner do.
  int run_first(int j) const { return run_first_[j]; }
  int run_last(int j) const { return run_last_[j]; }
  // Pairs off the runs with near-equal partners: along diagonal d (pairs (k - d, k)) the aggregates fall into cell
  // k + shift for k in [d, last] on a geometric grid (last < d: none; the rest goes through cell()).
  struct Diagonal {
    int shift, last;
  };
  const std::vector<Diagonal>& diagonals() const { return diagonals_; }
  // Lower extended pivot of the interval the packet of cell c is split over (Kumar et al. 2006, Eq. (15)).
  template <class T>
  int side(const Grid& g, int c, const T& b, const T& v) const {
    return v >= g.pivot(c) * b ? c : c - 1;
  }

 private:
  std::vector<int> cell_, run_first_, run_last_;
  std::vector<Diagonal> diagonals_;
  std::vector<double> vsum_;
};

}  // namespace granuflow::kernels
