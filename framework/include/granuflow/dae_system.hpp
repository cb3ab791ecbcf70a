// The assembled DAE F(t, y, y', p) = 0 of a finalized flowsheet: residual, exact Jacobian dF/dy + cj dF/dy'
// (per unit: forward AD over its local variables, coloured by the unit's per-class layout, plus the analytic part
// a unit may supply), quadrature rates, sensitivity residuals for named parameters, initial values, reported
// outputs and their exact sensitivities, and per-state metadata for the solvers.
//
// A DaeSystem is one run's view of a flowsheet: it reads the flowsheet's parameters once (run_params) and keeps
// every unit's Workspace, so several DaeSystems over one flowsheet can run in parallel threads.
//
// Implemented in src/dae_system.cpp (layout), dae_residual.cpp, dae_jacobian.cpp, dae_ad.cpp, dae_schur.cpp,
// dae_sensitivities.cpp and block_preconditioner.cpp; src/dae_internal.hpp holds what they share.
#pragma once
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/signals.hpp"

namespace granuflow {

// Compressed-sparse-column pattern of the Jacobian (union of the units' blocks).
struct SparsityPattern {
  int n = 0;
  std::vector<int> col_ptr;  // size n + 1
  std::vector<int> row_idx;  // size nnz, sorted within a column
  int nnz() const { return static_cast<int>(row_idx.size()); }
};

class DaeSystem {
 public:
  // Configures every unit (a workspace each) with the flowsheet's current parameters. The flowsheet must be
  // finalized and must outlive this object and stay unchanged while it runs; parameter changes need
  // reconfigure(). With `inline_explicit`, the states of explicit units (UnitSpec::set_explicit) are not unknowns
  // of the system: they are evaluated from the others before every residual and eliminated from the Jacobian by
  // the Schur complement J_RR - J_RS J_SS^-1 J_SR (dense Jacobians only).
  explicit DaeSystem(const Flowsheet& fs, bool inline_explicit = true);
  ~DaeSystem();
  void reconfigure();
  // Unit `u` was replaced by one of the same layout (a setting switched by an event, events_settings.hpp): its
  // workspace is made anew; reconfigure() before the next evaluation.
  void unit_replaced(int u);
  // For a system kept from an earlier run (Flowsheet::take_system): reconfigure(), segment start 0, counters 0.
  void begin_run();
  // A run that ends normally says so; only such systems are kept for the next run (one a unit or the integrator
  // threw out of may hold half-updated tables).
  void end_run() { completed_ = true; }
  bool completed() const { return completed_; }

  int size() const { return n_; }           // unknowns of the integrator
  int full_size() const { return n_ext_; }  // every state of the flowsheet, explicit ones last
  int n_quadratures() const { return n_quad_; }
  bool inlined() const { return inline_; }
  // Fraction of the entries of the Jacobian over all states that can be nonzero (the units' blocks).
  double fill() const { return fill_; }
  // The full state vector (explicit states evaluated) from the integrator's y, y'; explicit states' y' = 0.
  void extend(double t, const double* y, const double* yp, double* y_full, double* yp_full);
  // Sensitivities of all states from those of the unknowns (explicit ones by forward AD).
  void extend_sensitivities(double t, const double* y, const double* yp, const std::vector<int>& params,
                            const double* const* yS, double* const* yS_full);
  const Flowsheet& flowsheet() const { return fs_; }

  // Inputs with step interpolation are held at their value at the start of the current segment, so the
  // integrator never sees a jump inside a segment.
  void set_segment_start(double t) { segment_start_ = t; }

  Status residual(double t, const double* y, const double* yp, double* r);
  // Dense column-major n x n (ld = n) when `dense` != nullptr, else values in `pattern()` order.
  // With set_classes_local(true) the units may leave out the entries between two different size classes of their
  // populations (JacobianSink::classes_local): for a class-local Newton matrix, which does not read them.
  void set_classes_local(bool on) { classes_local_ = on; }
  // The class state blocks whose totals the pair processes conserve (ClassLayout::class_local_newton; each a list of
  // unknowns), and per block what the units left out of the last class-local Jacobian, summed over the block's rows
  // (n values, one per column; JacobianSink::left_out).
  const std::vector<std::vector<int>>& conserved_blocks() const;
  // (null before the first class-local Jacobian)
  const double* left_out(int block) const {
    return left_out_.empty() ? nullptr : left_out_.data() + size_t(block) * n_;
  }
  // The unknowns' values at that Jacobian (n values): where in a block what was left out goes.
  const double* left_out_at() const { return left_out_y_.empty() ? nullptr : left_out_y_.data(); }
  void jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse_values);
  // The same Jacobian by plain forward AD over every local column of every unit (no analytic parts, no colouring,
  // no reductions): the reference the structured Jacobian is tested against. Dense, without inlined units.
  void reference_jacobian(double t, const double* y, const double* yp, double cj, double* dense);
  const SparsityPattern& pattern() const {
    if (pattern_.col_ptr.empty()) build_sparse_maps();
    return pattern_;
  }

  // Sensitivity residuals r_k = F_y s_k + F_y' s'_k + F_p e_{p_k} for global parameter ids `params`.
  Status sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                       const double* const* yS, const double* const* ypS, double* const* rS);
  // Quadrature rates dq/dt at the integrator's y (explicit states evaluated inline), and their sensitivities.
  Status quadrature(double t, const double* y, const double* yp, double* qdot);
  Status quadrature_sens(double t, const double* y, const double* yp, const std::vector<int>& params,
                         const double* const* yS, double* const* qdotS);

  void initial_values(std::vector<double>& y0) const;
  void initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const;
  std::vector<double> differential_id() const;  // 1 differential, 0 algebraic
  std::vector<double> scales() const;
  // Per integrated state, the integrators' constraint: 1 for an inventory declared non-negative
  // (UnitSpec::set_nonnegative), 0 for none; empty when no state has one.
  std::vector<double> constraints() const;
  std::vector<double> quadrature_scales() const;
  // Reported outputs at the full state vector (see extend()) and the quadratures.
  void report(double t, const double* y_full, const double* yp_full, const double* q, double* out);
  // d outputs / d p_k for every parameter k in `params`, exact: the outputs evaluated with Jets carrying the
  // states' and quadratures' sensitivities (full vectors) and the parameters' own directions.
  void report_sensitivities(double t, const double* y_full, const double* yp_full, const double* q,
                            const std::vector<int>& params, const double* const* yS_full, const double* const* qS,
                            double* const* dout);
  // Unit and state name of a global row, for error messages.
  std::string describe_row(int row) const;

  // Preconditioner of the iterative linear solver (block_preconditioner.cpp): block-diagonal over the units, each
  // block the unit's own (Unit::precondition_setup/solve) or, for a unit without one, its exact own block
  // dF/dx + cj dF/dx' over its own states (analytic parts and forward AD), LU-factored. Couplings between units are
  // left to the Krylov iterations. setup() at (t, y, y', cj); solve() writes z = P^-1 r.
  void precondition_setup(double t, const double* y, const double* yp, double cj);
  void precondition_solve(double t, const double* y, const double* yp, double cj, const double* r, double* z);

  long residual_count() const { return n_res_; }
  long jacobian_count() const { return n_jac_; }

 private:
  struct AdPlan;
  class Recorder;
  class FactoringSink;
  class DenseSink;
  void record_left_out(int state, int col, double value);
  void fill_params(double t);
  void build_sparse_maps() const;
  void build_schur_structure();
  void check_explicit_residuals();
  void build_ad_plan(int u);
  template <class T>
  Ctx<T> ctx(int u, double t, const T* y, const T* yp, const std::vector<std::vector<T>>& params, T* r) const;
  template <class T>
  void evaluate_explicit(double t, T* x, T* xd, const std::vector<std::vector<T>>& params, std::vector<T>& scratch,
                         const std::vector<int>* only = nullptr);  // `only`: these explicit units (in order)
  // With `factor_outer`, explicit units' outer products are collected in outer_ instead of added to `dense`.
  void assemble(double t, const double* y, const double* yp, double cj, int dim, double* dense, double* sparse,
                bool factor_outer = false);
  void ad_unit(int u, double t, const double* y, const double* yp, double cj, JacobianSink& sink,
               const AdPlan* plan = nullptr);
  void seed(int id, int u, size_t slot, std::vector<Jet>& pj) const;
  void load_directions(const double* y, const double* yp, const std::vector<int>& params, size_t d0, size_t d1,
                       const double* const* yS, const double* const* ypS, int n_loaded);
  void params_as_jets();
  // Drives (signals.hpp) into `params`: those whose source is a state (readable from the integrated states alone), then
  // those whose source is an output (after the explicit states are evaluated); for unit `sink` only, or all (-1).
  template <class T>
  void drive_states(const T* y, std::vector<std::vector<T>>& params, int sink = -1) const;
  template <class T>
  void drive_outputs(double t, const T* y, const T* yp, std::vector<std::vector<T>>& params, int sink = -1);

  const Flowsheet& fs_;
  int n_;      // unknowns
  int n_ext_;  // all states
  int n_quad_ = 0;
  bool inline_ = false;
  bool classes_local_ = false;
  mutable std::vector<std::vector<int>> conserved_;  // conserved_blocks(), built on first use
  mutable std::vector<int> conserved_of_;            // per unknown its block, -1 if none
  std::vector<double> left_out_, left_out_y_;
  double fill_ = 0.0;
  std::vector<std::unique_ptr<Workspace>> ws_;  // per unit, this run's
  std::vector<int> explicit_order_;             // explicit units, each after the explicit units it reads
  std::vector<int> quad_explicit_;              // the explicit units the quadrature rates read, in that order
  std::vector<std::pair<int, int>> inputs_;     // (unit, parameter) of every parameter driven by an input
  std::vector<Drive> drives_;                   // parameters driven by signals (signals.hpp)
  bool output_drives_ = false;                  // some parameter is driven by an output
  std::vector<double> drive_out_, drive_quad_;  // a measured unit's outputs, zero quadratures
  std::vector<Jet> drive_out_j_, drive_quad_j_;
  std::vector<std::pair<int, int>> explicit_reads_;  // (u, v): explicit unit u reads explicit unit v, in order
  // u w^T on the rows of `unit` and the columns `cols`: outer_ for explicit units, rs_outer_ for integrated ones
  struct OuterTerm {
    int unit = -1;
    std::vector<double> u, w;
    std::vector<int> cols;
  };
  std::vector<OuterTerm> outer_;  // storage reused between Jacobians; the first n_outer_ are current
  size_t n_outer_ = 0;
  // u w^T on the rows of an integrated unit, columns explicit states (a sum over an inlined stream's classes, such as
  // a bed's total feed): kept factored, it enters the Schur complement as u (w^T Z), not as rows times Z.
  std::vector<OuterTerm> rs_outer_;
  size_t n_rs_outer_ = 0;
  class IntegratedSink;
  Eigen::MatrixXd schur_u_, schur_au_, schur_p_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> schur_c_;  // J_RS Z on the rows reading S
  Eigen::MatrixXd schur_jd_, schur_cd_;  // J_RS held dense and J_RS Z, when J_RS is dense enough (column updates)
  std::vector<int> schur_seen_;          // explicit column -> last Jacobian that listed it in schur_t_
  struct SparseRows {                    // compressed sparse rows
    std::vector<int> start{0}, col, next;
    std::vector<double> val;
    int rows() const { return static_cast<int>(start.size()) - 1; }
    // entries in any order; a repeated entry stays a second term of its row, which every use sums
    void assign(int n_rows, const std::vector<Eigen::Triplet<double>>& entries);
  };
  // dF_R/dy_R of an inlined Jacobian from the assembled rows (dae_schur.cpp): schur_complement() runs the others.
  void schur_complement(double* dense);
  void schur_rs();  // J_RS as triplets
  void schur_z();   // Z = J_SS^-1 J_SR by forward substitution
  void schur_subtract_z(double* dense);
  void schur_subtract_rs_outer(double* dense);
  void schur_subtract_outer(double* dense);
  void subtract_product(SparseRows& z, const SparseRows& s, const SparseRows& zv);
  // schur_acc_ += a * row r of z over the columns that row holds, each column listed once per stamp in `touched`
  void accumulate_row(const SparseRows& z, int r, double a, int stamp, std::vector<int>& touched);
  static OuterTerm& next_term(std::vector<OuterTerm>& terms, size_t& used, int unit, int n_rows, const double* u);
  std::vector<SparseRows> z_rows_;                             // per explicit unit: its rows of Z = J_SS^-1 J_SR
  std::vector<std::pair<const SparseRows*, int>> schur_zrow_;  // explicit column -> its unit's rows of Z, its row
  SparseRows s_rows_, product_rows_;
  std::vector<double> schur_acc_;
  std::vector<int> schur_mark_, schur_cols_touched_;
  std::vector<int> schur_pos_of_row_;  // integrated row -> position in schur_rows_, or -1
  int schur_stamp_ = 0;
  std::vector<Eigen::Triplet<double>> schur_t_;                   // J_RS
  std::vector<std::vector<Eigen::Triplet<double>>> zs_triplets_;  // per unit: an explicit unit's J_SR rows
  std::vector<std::vector<Eigen::Triplet<double>>> read_blocks_;  // per explicit read (u, v): J_SS block
  std::vector<int> read_index_;                                   // u * units + v -> index in explicit_reads_, or -1
  std::vector<int> schur_rows_, schur_cols_;                      // where the Schur correction can be nonzero
  std::vector<int> schur_col_pos_;                                // integrated column -> position in schur_cols_, or -1
  std::vector<std::tuple<int, int, int>> schur_row_runs_;         // (position in schur_rows_, first row, length)
  std::vector<double> y_ext_, yp_ext_, jac_ext_, scratch_;
  bool ext_clean_ = false;  // jac_ext_ is all zeros (the Schur pass of the last evaluation cleared what it read)
  double segment_start_ = 0.0;
  std::vector<std::vector<double>> pvals_;      // per unit, at the last fill time
  std::vector<std::vector<double>> pconst_;     // per unit, the run's values at t = 0 (links applied)
  std::vector<std::vector<int>> local_cols_;    // per unit: global columns its rows depend on
  std::vector<std::unique_ptr<AdPlan>> plans_;  // per unit: how its AD sweeps seed directions
  // Sparse structure, built on first use (dense runs never need it).
  mutable std::vector<std::vector<int>> block_pos_;            // per unit: row-major [local row][local col] -> position
  mutable std::vector<std::unordered_map<int, int>> col_map_;  // per unit: global column -> local column
  mutable SparsityPattern pattern_;
  std::vector<Jet> xj_, xdj_, rj_, jet_scratch_, qj_;
  // xj_ and xdj_ below this index carry zero derivative parts (the Jacobian's sweeps restore the zeros they seed), so
  // a Jacobian only writes their values; paths that load directions lower it.
  int jets_plain_ = 0;
  std::vector<std::vector<Jet>> pj_;  // per unit: parameters as Jets (seeded for sensitivities)
  std::vector<double> rbuf_;
  struct BlockPreconditioner;
  std::shared_ptr<BlockPreconditioner> prec_;  // shared_ptr: the type is complete in block_preconditioner.cpp only
  long n_res_ = 0, n_jac_ = 0;
  bool completed_ = false;
};

}  // namespace granuflow
