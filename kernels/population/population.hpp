// The population-balance engine: one implementation of aggregation, breakage and growth on a size grid that every
// particle-holding unit uses (batch and continuous beds, spray- and drying-zone compartments, the verification
// unit). A unit owns one Population per population it holds and calls it from its residual.
//
// State: particle numbers N_i per class on a Grid (volume pivots x_i) and any number P of extensive properties per
// class q_{p,i} (water mass, liquid volume, enthalpy ...). Aggregation and breakage move a property with the volume
// of the particles that carry it: a particle of class i carries pi_i = q_i / (N_i + f_i) (f_i a small floor that keeps
// an emptied class finite), an aggregate carries the sum of its partners', fragments the parent's share of volume.
// Number, volume and every property are conserved in the discrete equations to round-off. Growth (layering) moves
// number by the finite-volume fluxes, and properties with them from the donor cell.
//
// Mechanisms are plugins chosen by name in the unit's settings (kernels/registry.hpp): aggregation kernel and scheme
// (fixed_pivot, cell_average), breakage selection rate, fragment distribution and scheme (fixed_pivot, cell_average,
// cell_mass), growth law and scheme (fv_koren, fv_upwind). A mechanism not named has no parameters and no cost. The
// kernels' parameters are declared in the unit (one table per kernel, with the kernel's SI units, bounds and source).
// The engine knows the schemes only through their interfaces: an aggregation scheme forms the events from the
// engine's pair coefficients and places them (discretization/aggregation_scheme.hpp), with its grid-only tables built
// once in declare() and its tables of the kernel's values in the run's Work; a breakage scheme builds (and keeps) the
// fragment matrix. A kernel-parameter change rebuilds only the tables of the mechanism that owns the parameter.
//
// Files: population.cpp (declare, configure, refresh), population_rates.cpp (the rates, aggregation's and growth's
// parts), population_breakage.cpp, population_jacobian.cpp (analytic and AD Jacobians), population_work.hpp (Work).
//
// Leaving the grid, the one way for every unit: aggregates beyond the top pivot, fragments below the first and
// particles grown past either end are counted in the outside rates (number/volume above, volume below, and each
// property above/below). With Outside::kFold (paper 001) they are put back into the end class with their volume
// and properties (the number then changes, mass does not); with kRemove they leave and the unit integrates the
// outside rates so that its balances close.
//
// Jacobians: analytic for everything built in (the kernels' derivatives come from small forward-AD evaluations per
// class and per pair, never from hand derivations); forward AD over the engine's inputs where no analytic path
// exists (a kernel that reads N).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "aggregation/aggregation_kernel.hpp"
#include "breakage/fragment_distribution.hpp"
#include "breakage/selection_rate.hpp"
#include "discretization/aggregation_scheme.hpp"
#include "discretization/breakage_scheme.hpp"
#include "discretization/fv_growth.hpp"
#include "discretization/grid.hpp"
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
#include "growth/growth_law.hpp"

namespace granuflow {
class Settings;
}

namespace granuflow::kernels {

enum class Outside { kFold, kRemove };
inline constexpr int kMaxProperties = 8;  // extensive properties a population carries per class

// What a unit decides about its population: defaults of the mechanism settings, and the prefixes under which the
// kernels' parameters and settings appear in the unit ("" keeps the kernels' own names, as the fluid bed does).
struct PopulationOptions {
  std::string aggregation = "none", aggregation_scheme = "cell_average";
  std::string breakage = "none", fragments = "uniform_binary", breakage_scheme = "cell_average";
  std::string growth = "none", growth_scheme = "fv_koren";  // growth "": no growth setting (the unit grows itself)
  Outside outside = Outside::kRemove;
  std::string agg_prefix = "agg_", sel_prefix = "sel_", frag_prefix = "frag_", growth_prefix = "growth_";
  std::string agg_settings = "agg_", sel_settings = "sel_", frag_settings = "frag_", growth_settings = "growth_";
  std::vector<std::string> properties;  // names of the carried properties (water, ...)
};

// The rows of the outside rates (kOutNumberAbove ..., out_property_above/below): discretization/aggregation_scheme.hpp.

class Population {
 public:
  // The inputs of one evaluation. Arrays are per class; `q[p]` per property; fields null unless needs() asks.
  template <class T>
  struct State {
    const T* N = nullptr;
    const T* q[kMaxProperties] = {};
    const T* floor = nullptr;  // f_i of pi_i = q_i / (N_i + f_i); null: 0
    const T* fields[kFields] = {nullptr, nullptr, nullptr, nullptr, nullptr};
    const T* p = nullptr;  // the unit's parameters; the kernels read theirs at the offsets declare() gave them
  };
  // Rates are added (not assigned) to dN (n), dq[p] (n), outside (outside_rows(), may be null) and grown (the
  // volume growth creates, m^3/s, may be null).
  template <class T>
  struct Rates {
    T* dN = nullptr;
    T* dq[kMaxProperties] = {};
    T* outside = nullptr;
    T* grown = nullptr;
  };
  // Where the engine's inputs and rates sit in the unit's Jacobian. Input columns: N_i = N_scale[i] * y[N_col[i]]
  // (a unit with mass states gives 1 / particle mass), q_{p,i} = y[q_col[p][i]], field f of class i =
  // y[field_col[f][i]]
  // (-1: a constant). Rows: the unit's residual row of class i's number rate is N_row[i] and contains
  // N_factor[i] * dN_i/dt (- m_i for a mass residual M_i' - m_i dN_i/dt); properties likewise with q_factor;
  // outside_row[k] (-1: none) with factor -1.
  struct Map {
    std::vector<int> N_col, N_row;
    std::vector<double> N_scale, N_factor;
    std::vector<std::vector<int>> q_col, q_row;
    double q_factor = -1.0;
    std::vector<int> field_col[kFields];
    std::vector<int> outside_row;
    int grown_row = -1;  // the row of the volume growth creates (factor -1), or -1
  };
  struct Work;
  struct WorkDeleter {
    void operator()(Work* w) const;
  };
  using WorkPtr = std::unique_ptr<Work, WorkDeleter>;

  Population();
  ~Population();
  Population(Population&&) noexcept;
  Population& operator=(Population&&) noexcept;

  // Reads the mechanism settings (names and the kernels' own settings) and declares the kernels' parameters.
  void declare(UnitSpec& s, Settings& st, std::shared_ptr<const Grid> grid, const PopulationOptions& options);
  const Grid& grid() const { return *grid_; }
  int size() const { return n_; }
  int properties() const { return static_cast<int>(property_names_.size()); }
  int outside_rows() const { return 3 + 2 * properties(); }
  Outside outside() const { return outside_; }
  bool aggregation() const { return agg_.kernel != nullptr; }
  bool breakage() const { return sel_.kernel != nullptr; }
  bool growth() const { return growth_.kernel != nullptr; }
  // Fields the kernels read (the unit supplies them in State::fields), and whether they read N itself.
  const ClassNeeds& needs() const { return needs_; }

  WorkPtr make_work() const;
  // Once per run: the kernels' checks (naming `where`) and the tables that depend on parameters only.
  void configure(Work& w, const double* p, const std::string& where) const;

  // How double evaluations sum aggregation after configure(): "separable" (prefix sums over the kernel's
  // factor_terms), "matrices" (pair matrices of a size-only kernel), "pairs" (the pair loop) or "none".
  std::string aggregation_evaluation(const Work& w) const;

  void rates(Work& w, const State<double>& s, const Rates<double>& r) const;
  void rates(Work& w, const State<Jet>& s, const Rates<Jet>& r) const;
  // Adds d(rates)/d(inputs), mapped by `m`, to the sink.
  void jacobian(Work& w, const State<double>& s, const Map& m, JacobianSink& sink) const;

 private:
  template <class K>
  struct Plugin {
    std::unique_ptr<K> kernel;
    int first = 0, count = 0;
  };
  template <class K>
  Plugin<K> plugin(UnitSpec& s, Settings& st, const Registry<K>& reg, const std::string& name,
                   const std::string& param_prefix, const std::string& setting_prefix);
  template <class T>
  void rates_t(Work& w, const State<T>& s, const Rates<T>& r, bool fold) const;
  // The mechanisms' rates into the work rows dN (n), dq (P x n) and out (outside rows), in the order rates_t adds
  // them; growth returns the volume it creates.
  template <class T>
  void aggregation_rates(Work& w, const State<T>& s, const ClassState<T>& cs, T* dN, T* dq, T* out) const;
  template <class T>
  void breakage_rates(Work& w, const State<T>& s, const ClassState<T>& cs, T* dN, T* dq, T* out) const;
  template <class T>
  T growth_rates(Work& w, const State<T>& s, T* dN, T* dq, T* out) const;
  // The growth law's terms at the scheme's faces (in the scratch of T), the fluxes' arrays sized.
  template <class T>
  GrowthTerms<T> growth_terms(Work& w, const T* p) const;
  template <class T>
  ClassState<T> class_state(const State<T>& s) const;
  template <class T>
  bool fresh_tables(const Work& w, const T* p, int first, int count) const;
  void refresh(Work& w, const double* p) const;
  // The engine's Jacobian D (jacobian_rows() x input_cols(), column-major): rates of the class numbers, the
  // properties, the outside rows and the volume growth creates, against N, q and the fields read.
  // `local`: only the entries within one class (and the rows outside the grid), JacobianSink::classes_local.
  void analytic_jacobian(Work& w, const State<double>& s, std::vector<double>& D, bool local) const;
  void aggregation_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const;
  void aggregation_local_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const;
  // Whether the aggregation scheme can give the class-local births (asked once per run).
  bool local_births_known(Work& w) const;
  void feature_gradients(Work& w, const State<double>& s, std::vector<double>& phi, std::vector<double>& G) const;
  void breakage_jacobian(const Work& w, const PopulationJacobian& J, bool local) const;
  void growth_jacobian(Work& w, const State<double>& s, const PopulationJacobian& J) const;
  void ad_jacobian(Work& w, const State<double>& s, std::vector<double>& D) const;
  void fold_rows(double* D, int cols) const;
  int input_cols() const;  // N, q, fields read
  int jacobian_rows() const { return n_ * (1 + properties()) + outside_rows() + 1; }

  std::shared_ptr<const Grid> grid_;
  int n_ = 0;
  std::vector<std::string> property_names_;
  Outside outside_ = Outside::kRemove;
  ClassNeeds needs_;
  std::vector<int> field_index_;  // fields read, in Field order
  Plugin<AggregationKernel> agg_;
  std::unique_ptr<AggregationScheme> agg_scheme_;
  Plugin<SelectionRate> sel_;
  Plugin<FragmentDistribution> frag_;
  std::unique_ptr<BreakageScheme> brk_scheme_;
  Plugin<GrowthLaw> growth_;
  std::unique_ptr<FvGrowth> growth_scheme_;
  std::vector<int> kernel_params_;  // indices of every kernel parameter (the refresh snapshot)
};

}  // namespace granuflow::kernels
