// A third aggregation scheme, written for the tests from scratch on the scheme interface alone
// (kernels/discretization/aggregation_scheme.hpp): it shows that a scheme is one file pair registered by name, with no
// edit to the population engine. "two_point_split": the aggregate of pair (j, k), volume v = x_j + x_k, goes to the
// pivot nearest below it and the one above, in the shares that keep number and volume (1 - nu and nu with
// nu = (v - x_lo) / (x_hi - x_lo)); beyond the top pivot the upper share leaves at the virtual pivot, beyond the
// virtual pivot the aggregate leaves whole. Properties follow the volume. Every pair is placed on its own (no runs,
// no matrices): simple, and slower than the built-in schemes.
//
// It counts its grid-only builds (setup) and its refreshes after a kernel-parameter change, so that a test can tell
// which one a parameter change triggers.
#pragma once
#include <atomic>
#include <string>
#include <vector>

#include "kernels/discretization/aggregation_scheme.hpp"

namespace granuflow::test_scheme {

class TwoPointSplit : public kernels::AggregationScheme {
 public:
  static constexpr const char* kName = "two_point_split";
  // Registers the scheme in the process-wide registry (once; later calls do nothing).
  static void register_once();
  static std::atomic<int> setups, refreshes;

  std::string name() const override { return kName; }
  void setup(const kernels::Grid& g) override;
  std::unique_ptr<Tables> make_tables() const override;
  void refresh(Tables& t, const kernels::AggregationTableInputs& in) const override;
  void rates(Tables& t, const kernels::AggregationArgs<double>& a) const override;
  void rates(Tables& t, const kernels::AggregationArgs<Jet>& a) const override;
  void jacobian_row(Tables& t, const kernels::PopulationJacobian& J, const kernels::PairEvent* events,
                    int count) const override;

  // Where the aggregate of one pair goes: two shares (the second may leave the grid) or the whole (leaves).
  struct Share {
    int cls;        // class, or -1: above the grid
    double number;  // particles per event
    double volume;  // volume per event (number times the pivot it lands on)
  };
  struct Destination {
    Share share[2];
    int count;
    double v;  // the aggregate's volume
  };

 private:
  template <class T>
  void rates_t(const kernels::AggregationArgs<T>& a) const;
  void births_jacobian(const kernels::PopulationJacobian& J, const kernels::PairEvent& e) const;
  std::vector<Destination> dest_;
};

}  // namespace granuflow::test_scheme
