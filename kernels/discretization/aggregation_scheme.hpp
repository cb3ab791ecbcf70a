// Numerical schemes for aggregation: where the aggregate of every pair of classes lands on the grid. The population
// engine (kernels/population/population.hpp) forms the pair coefficients h K_jk (h = 1/2 for like pairs) and the
// efficiencies E_jk; the scheme forms the event rates r = h K_jk E_jk N_j N_k (paper 001, Eqs. (21), (24)), removes
// the partners and places the aggregates, keeping number and volume in the discrete equations
//     number:  sum_i dN_i/dt + d(number_above)/dt = -1/2 sum_{j,k} beta_jk N_j N_k   (one particle per event)
//     volume:  sum_i x_i dN_i/dt + d(volume_above)/dt = 0
// (docs/verification.md "Conservation"). Extensive properties carried by the particles (water, liquid volume ...) go
// where the aggregate's volume goes, in the same fractions, so they are conserved exactly too.
//
// A scheme is a strategy the engine only sees through this interface: a new one is a file pair registered by name
// (kernels/registry.hpp), with no edit to the engine. What depends on the grid only it builds in setup(), once per
// grid; what depends on the kernel's values (the pair coefficients, tables derived from them) it keeps in its
// Tables, one per run (Population::Work), rebuilt by refresh() when a kernel parameter changes. Registered:
// fixed_pivot (Kumar & Ramkrishna 1996) and cell_average (Kumar et al. 2006).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "aggregation/aggregation_kernel.hpp"
#include "discretization/grid.hpp"

namespace granuflow::kernels {

// Pair-index arithmetic of the upper triangle j <= k, row-major.
inline size_t pair_count(int n) { return size_t(n) * (n + 1) / 2; }
inline size_t pair_index(int j, int k, int n) { return size_t(j) * n - size_t(j) * (j - 1) / 2 + (k - j); }

// Rows of the outside rates: number/volume above the top, volume below the bottom, then property p above and below.
inline constexpr int kOutNumberAbove = 0, kOutVolumeAbove = 1, kOutVolumeBelow = 2;
inline int out_property_above(int p) { return 3 + 2 * p; }
inline int out_property_below(int p) { return 4 + 2 * p; }

// One evaluation of the aggregation rates. Inputs per class (N, pi: P x n per-particle properties) and per pair
// (Kh = h K_jk, E = E_jk or null for a size-only kernel); the rates are added to dN (n), dq (P x n) and out (the
// outside rows above).
template <class T>
struct AggregationArgs {
  const Grid* grid = nullptr;
  int n = 0, P = 0;
  const T* N = nullptr;
  const T* pi = nullptr;
  const T* Kh = nullptr;
  const T* E = nullptr;
  T* dN = nullptr;
  T* dq = nullptr;
  T* out = nullptr;
};

// What a kernel-parameter change gives the scheme: the new size factor K (n x n, symmetric) and Kh per pair, the
// kernel and its parameters (for its separable form, AggregationKernel::factor_terms), and the properties carried.
struct AggregationTableInputs {
  const Grid* grid = nullptr;
  int P = 0;
  const std::vector<double>* K = nullptr;
  const std::vector<double>* Kh = nullptr;
  const AggregationKernel* kernel = nullptr;
  const ClassState<double>* cs = nullptr;
  const double* p = nullptr;
};

// One event of pair pr = (j, k) at `rate`, and d(rate)/d(input column) for the inputs it reads [begin, end).
struct PairEvent {
  struct Input {
    int col;
    double d;
  };
  size_t pr;
  int j, k;
  double rate;
  const Input *begin, *end;
  // f(input) for each input in order; the two of a size-only kernel's event (N_j, N_k) as straight-line code (a loop
  // over them cost the fixed pivot's Jacobian 50 % more at 110 classes).
  template <class F>
  void for_inputs(F&& f) const {
    if (end - begin == 2) {
      f(begin[0]), f(begin[1]);
    } else {
      for (const Input* in = begin; in != end; ++in) f(*in);
    }
  }
};

// The analytic Jacobian (column-major, R rows: class numbers, properties, outside rows; C input columns: N, q, fields)
// and the per-particle properties with their derivatives, as the engine lays them out.
struct PopulationJacobian {
  const Grid* grid = nullptr;
  int n = 0, P = 0, C = 0;
  size_t R = 0;
  double* D = nullptr;
  const double *pi = nullptr, *dpi_dN = nullptr, *dpi_dq = nullptr;
  size_t rowN(int i) const { return size_t(i); }
  size_t rowQ(int p, int i) const { return size_t(n) * (1 + p) + i; }
  size_t rowO(int k) const { return size_t(n) * (1 + P) + k; }
  int colQ(int p, int i) const { return n * (1 + p) + i; }
  void add(size_t r, int c, double v) const { D[size_t(c) * R + r] += v; }
  // The deaths of both partners of an event, with their properties: the same for every scheme.
  void deaths(const PairEvent& e) const {
    const int j = e.j, k = e.k;
    e.for_inputs([&](const PairEvent::Input& in) {
      add(rowN(j), in.col, -in.d);
      add(rowN(k), in.col, -in.d);
      for (int p = 0; p < P; ++p) {
        add(rowQ(p, j), in.col, -in.d * pi[size_t(p) * n + j]);
        add(rowQ(p, k), in.col, -in.d * pi[size_t(p) * n + k]);
      }
    });
    for (int p = 0; p < P; ++p)
      for (int i : {j, k}) {
        add(rowQ(p, i), i, -e.rate * dpi_dN[size_t(p) * n + i]);
        add(rowQ(p, i), colQ(p, i), -e.rate * dpi_dq[size_t(p) * n + i]);
      }
  }
};

class AggregationScheme {
 public:
  // Per run: what the scheme derives from the kernel's values, and its work arrays.
  struct Tables {
    virtual ~Tables() = default;
  };
  virtual ~AggregationScheme() = default;
  virtual std::string name() const = 0;
  // The grid-only tables, once per grid.
  virtual void setup(const Grid& g) = 0;
  virtual std::unique_ptr<Tables> make_tables() const { return std::make_unique<Tables>(); }
  // After a kernel-parameter change: only what depends on the kernel's values.
  virtual void refresh(Tables& /*t*/, const AggregationTableInputs& /*in*/) const {}
  // How double evaluations sum the pairs after refresh(): "pairs" unless the scheme has a faster form.
  virtual std::string evaluation(const Tables& /*t*/) const { return "pairs"; }
  // Adds the aggregation rates (deaths and births) to args' rows.
  virtual void rates(Tables& t, const AggregationArgs<double>& args) const = 0;
  virtual void rates(Tables& t, const AggregationArgs<Jet>& args) const = 0;
  // Analytic Jacobian, one row of the pair triangle at a time: the events of the pairs (j, k), k = j ... n - 1, in
  // order, rows j = 0 ... n - 1 in order, between jacobian_start() and jacobian_finish(). For each event the scheme
  // adds J.deaths(e), then the births, so that every entry of D receives its terms pair by pair. A row per call, not a
  // pair: the scheme's loop over the events has no call in it.
  virtual void jacobian_start(Tables& /*t*/, const PopulationJacobian& /*J*/) const {}
  virtual void jacobian_row(Tables& t, const PopulationJacobian& J, const PairEvent* events, int count) const = 0;
  virtual void jacobian_finish(Tables& /*t*/, const PopulationJacobian& /*J*/) const {}
  // What one event of pair (j, k), j <= k, places in the larger partner's own class k (`stay`: particles per event
  // and share of the carried properties) and above the grid (`out_volume` per event, `out_share` of the properties):
  // the births a class-local Jacobian keeps (Population::aggregation_local_jacobian). Filled per pair of the triangle,
  // from the grid alone; false if the scheme's placement depends on the state (the engine forms the whole Jacobian).
  struct LocalBirths {
    double stay = 0.0, stay_share = 0.0, out_volume = 0.0, out_share = 0.0;
  };
  virtual bool local_births(std::vector<LocalBirths>& /*per_pair*/) const { return false; }
};

}  // namespace granuflow::kernels
