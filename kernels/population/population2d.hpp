// The population-balance engine over two internal coordinates, solid volume and liquid volume (paper 002,
// Eqs. (6)-(10)): number densities N_a on a Grid2D (bins a = (i, j), solid class i, liquid class j), aggregation by
// any registered kernel, and the two ways liquid moves particles along the liquid axis: droplets deposited one at a
// time (paper 002, section 3.2: a droplet that meets a particle is absorbed by that particle whole) and drying.
//
// It is the engine of kernels/population used along a second axis, not a new one: the same kernel plugins and
// registry (an AggregationKernel's factor K_ik over the solid classes, its features and efficiency per bin), the same
// fixed-pivot table of the solid grid (FixedPivotAggregation: where s_i + s_k lands, number and volume kept) and the
// same conventions (event rate 1/2 beta N N per ordered pair, outside rates for what leaves the grid).
//
// Aggregation of bins a = (i, j) and b = (k, m): the aggregate has solid s_i + s_k, split between the solid pivots
// around it by the fixed-pivot rule, and liquid l_j + l_m = l_{j+m} exactly (grid2d.hpp). Number, solid volume and
// liquid volume are conserved in the discrete equations to round-off; what lands beyond the solid grid or the
// liquid axis leaves and is counted in the outside rows (number, solid volume, liquid volume).
//
// Two evaluations of the same equations:
//   * direct: the loop over every pair of bins, O(n^2) for n bins, any kernel, double and Jet;
//   * convolution (double only, kernels whose efficiency factors, AggregationKernel::efficiency_terms): for each pair
//     of solid classes the liquid direction is a convolution of two rows, done by real FFTs, O(ns^2 nl) instead of
//     O(ns^2 nl^2). Both are tested against each other; deaths use the factored sums in both cases.
//
// Jacobians: the analytic d(rates)/dN (aggregation is bilinear in N and beta does not depend on N: the liquid content
// of a bin is that of its pivot), for direct linear solvers at moderate sizes; for iterative ones the engine gives
// the death rates per particle, the diagonal of the dominant part, to build preconditioners from.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "aggregation/aggregation_kernel.hpp"
#include "discretization/fixed_pivot.hpp"
#include "discretization/grid2d.hpp"
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"

namespace granuflow {
class Settings;
}

namespace granuflow::kernels {

// Rows of the outside rates of a 2-D population: particles that left the grid, their solid and liquid volume.
inline constexpr int kOut2Number = 0, kOut2Solid = 1, kOut2Liquid = 2, kOut2Rows = 3;

enum class Evaluation2D { kAuto, kConvolution, kDirect };

struct Population2DOptions {
  std::string aggregation = "none";
  std::string agg_prefix = "agg_", agg_settings = "agg_";
};

class Population2D {
 public:
  struct Work;
  struct WorkDeleter {
    void operator()(Work* w) const;
  };
  using WorkPtr = std::unique_ptr<Work, WorkDeleter>;

  Population2D();
  ~Population2D();
  Population2D(Population2D&&) noexcept;
  Population2D& operator=(Population2D&&) noexcept;

  // Reads the aggregation kernel's name (setting `aggregation`) and its settings, declares its parameters, and the
  // setting `aggregation_evaluation` (auto | convolution | direct).
  void declare(UnitSpec& s, Settings& st, std::shared_ptr<const Grid2D> grid, const Population2DOptions& o);
  const Grid2D& grid() const { return *grid_; }
  int size() const { return grid_->size(); }
  bool aggregation() const { return agg_ != nullptr; }
  // The convolution path is used (kernel factors and the setting allows it).
  bool convolution() const { return conv_; }
  const AggregationKernel* kernel() const { return agg_.get(); }

  WorkPtr make_work() const;
  // Once per run: the kernel's checks (naming `where`) and the tables that depend on parameters only.
  void configure(Work& w, const double* p, const std::string& where) const;

  // Aggregation rates added to dN (one per bin) and out (kOut2Rows). `p`: the unit's parameters.
  void aggregation_rates(Work& w, const double* N, const double* p, double* dN, double* out) const;
  void aggregation_rates(Work& w, const Jet* N, const Jet* p, Jet* dN, Jet* out) const;
  // The same by the pair loop, whatever the setting (tests and benchmarks).
  void aggregation_direct(Work& w, const double* N, const double* p, double* dN, double* out) const;
  // d(aggregation rates)/dN times `factor` added to the sink: bin a's rate at local row rows[a], outside row k at
  // rows[n + k] (-1: none), N_b at global column cols[b].
  void aggregation_jacobian(Work& w, const double* N, const double* p, const std::vector<int>& rows,
                            const std::vector<int>& cols, double factor, JacobianSink& sink) const;
  // d_a = sum_b beta_ab N_b, the rate at which one particle of bin a aggregates (1/s).
  void death_rates(Work& w, const double* N, const double* p, double* d) const;

 private:
  template <class T>
  void direct(Work& w, const T* N, const T* p, T* dN, T* out) const;
  void convolve(Work& w, const double* N, double* dN, double* out) const;
  void refresh(Work& w, const double* p) const;
  void factored_deaths(Work& w, const double* N, double* d) const;

  std::shared_ptr<const Grid2D> grid_;
  std::unique_ptr<AggregationKernel> agg_;
  int first_ = 0, count_ = 0;  // the kernel's parameters in the unit
  FixedPivotAggregation targets_;
  Evaluation2D evaluation_ = Evaluation2D::kAuto;
  bool conv_ = false;
};

}  // namespace granuflow::kernels
