// Fixed pivot technique (Kumar & Ramkrishna 1996, Chem. Eng. Sci. 51, Eqs. (9)-(10)) for aggregation: each
// aggregate of volume v = x_j + x_k is split between the two pivots around it so that number and volume are kept.
// The split depends on the grid only, so it is tabulated once per pair. An aggregate beyond the top pivot splits
// between x_{n-1} and the virtual pivot x_hi, the part at x_hi leaving the grid ("above"); beyond x_hi it leaves
// whole.
#pragma once
#include "discretization/aggregation_scheme.hpp"

namespace granuflow::kernels {

class FixedPivotAggregation : public AggregationScheme {
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
  const Target& target(size_t pair) const { return targets_[pair]; }
  double volume(size_t pair) const { return vsum_[pair]; }

 private:
  std::vector<Target> targets_;
  std::vector<double> vsum_;
};

}  // namespace granuflow::kernels
