// Fixed pivot technique (Kumar & Ramkrishna 1996, Chem. Eng. Sci. 51, Eqs. (9)-(10)) for aggregation: each
// aggregate of volume v = x_j + x_k is split between the two pivots around it so that number and volume are kept.
// The split depends on the grid only, so it is tabulated once per pair. An aggregate beyond the top pivot splits
// between x_{n-1} and the virtual pivot x_hi, the part at x_hi leaving the grid ("above"); beyond x_hi it leaves
// whole. The engine's sums over the pairs are those shared with the cell average (pair_runs.hpp).
#pragma once
#include "discretization/aggregation_scheme.hpp"
#include "discretization/pair_runs.hpp"

namespace granuflow::kernels {

class FixedPivotAggregation : public RunScheme<FixedPivotAggregation> {
 public:
  struct Target {
    int lo;       // lower class, or -1
    int hi;       // upper class, or -1: the upper part leaves the grid at the top
    double w_lo;  // particles placed per event
    double w_hi;
    double f_lo;  // fraction of the aggregate's volume placed
    double f_hi;
  };
  std::string name() const override { return "fixed_pivot"; }
  void setup(const Grid& g) override;
  void jacobian_row(Tables& t, const PopulationJacobian& J, const PairEvent* events, int count) const override;
  bool local_births(std::vector<LocalBirths>& per_pair) const override;
  const Target& target(size_t pair) const { return targets_[pair]; }
  double volume(size_t pair) const { return vsum_[pair]; }
  // For the engine's vectorized pair loop: the partners k of class j in [run_first(j), run_last(j)] (possibly empty)
  // place their aggregates on k and k + 1, as most pairs do on any grid; the weights as arrays over the pairs, 0 for
  // the pairs off the runs (whose aggregates go elsewhere: target()).
  int run_first(int j) const { return run_first_[j]; }
  int run_last(int j) const { return run_last_[j]; }
  const double* w_lo() const { return w_lo_.data(); }
  const double* w_hi() const { return w_hi_.data(); }
  const double* f_lo() const { return f_lo_.data(); }
  const double* f_hi() const { return f_hi_.data(); }
  // Pairs off the runs with near-equal partners (k - j = d small): on a geometric grid each diagonal d places all its
  // aggregates with one shift and one set of weights, so the engine sums them as vector loops over k. Diagonal d
  // covers the pairs (k - d, k) for k in [d, last] (last < d: none; the rest goes through target()).
  struct Diagonal {
    int shift, last;  // aggregates of pair (k - d, k) land on k + shift and k + shift + 1
    double w_lo, w_hi, f_lo, f_hi;
  };
  const std::vector<Diagonal>& diagonals() const { return diagonals_; }

 private:
  std::vector<Target> targets_;
  std::vector<double> vsum_, w_lo_, w_hi_, f_lo_, f_hi_;
  std::vector<int> run_first_, run_last_;
  std::vector<Diagonal> diagonals_;
};

}  // namespace granuflow::kernels
