// The unit-model interface.
//
// A unit declares, once, its states (differential or algebraic, SI unit, typical scale), its parameters
// (ParamSpec), its ports, its quadratures and its reported outputs, each through a typed handle (StateId,
// ParamId, PortId, QuadId, OutputId) that the residual then uses: no positional enum has to follow the order of
// the declarations. Its residual is written once as a template on the scalar type T:
//
//     F_k(t, x, xdot, p) = 0   for every own state k (one equation per state, written to c.res(k)),
//
// where x holds the unit's own states and, through its ports, the fields provided by connected units. The
// framework owns the solver: Jacobians (forward AD over the unit's local variables, coloured by the unit's
// per-class structure, plus an analytic part the unit may supply), linear solves, consistent initialization,
// quadratures and input breakpoints.
//
// Contract: eval() writes every res(k) for k < number of own states; it returns Status::kRecoverable to make
// the integrator cut the step (e.g. a mass went negative), kFatal to stop. A unit object is immutable once
// declared: everything a run computes or caches lives in the unit's Workspace, one per run, so one flowsheet
// can be simulated from several threads at once.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "granuflow/ad.hpp"
#include "granuflow/param.hpp"
#include "granuflow/stream.hpp"

namespace granuflow {

// A differential state k has the residual y'_k - f(y, p, t) (no other dependence on y'): the simulator relies on it
// to reuse Jacobians across steps, and checks it on the first evaluation of each run (falling back to fresh ones).
enum class StateKind { Differential, Algebraic };
enum class Status { kOk = 0, kRecoverable = 1, kFatal = -1 };

// Typed handles returned by the declarations; -1 is "not declared" (a mechanism a scene left out).
struct StateId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
  StateId operator+(int k) const { return {i + k}; }  // the k-th of a block of consecutive states
};
struct ParamId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
};
struct PortId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
};
struct OutputId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
  OutputId operator+(int k) const { return {i + k}; }
};
struct QuadId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
};
struct ReductionId {
  int i = -1;
  explicit operator bool() const { return i >= 0; }
};

struct StateSpec {
  std::string name;
  StateKind kind;
  std::string unit;
  double scale;              // typical magnitude: absolute tolerance = atol * scale
  bool accumulator = false;  // integrates a flow no equation reads (what left a grid): outside a steady state
  bool nonnegative = false;  // an inventory (class mass, particle number): a run fails when it goes negative
  bool enforced = true;      // a nonnegative state is also held there by the integrator's constraints
};

struct PortSpec {
  std::string name;
  StreamKind kind = nullptr;
  PortDir dir = PortDir::In;
  int classes = 0;            // per-class streams: number of size classes
  bool optional = false;      // may stay unconnected: its read fields are then zero (a mechanism left out)
  std::vector<double> grid;   // per-class streams: pivot diameters (m); connected ports must agree
  std::vector<int> provided;  // per field: own state index providing it, or -1 (read from the peer)
  std::vector<std::pair<int, int>> forwarded;  // per field: (in port, field) whose source this field passes on, or -1
};

// What an output means to the tools that read results (balance closure, size distributions, warnings), declared
// instead of encoded in its name.
enum class OutputRole {
  kValue,           // a reported quantity
  kBalanceIn,       // cumulative inflow of `quantity` (water, solids, energy) since t = 0
  kBalanceOut,      // cumulative outflow
  kBalanceHold,     // current hold-up
  kSizeDiameter,    // pivot diameter of class `cls` of a size distribution, m
  kSizeMass,        // mass in class `cls` of a size distribution, kg
  kRegularization,  // count of classes/instances where a closure left the published equation (floor, cap)
  kGridEnd,         // fraction of a population's mass in its end classes (the grid may be too short)
};

struct OutputSpec {
  std::string name;
  std::string unit;
  OutputRole role = OutputRole::kValue;
  std::string quantity;  // balances: water | solids | energy
  int cls = -1;          // size distributions: class index
  std::string description;
};

struct QuadSpec {
  std::string name;
  std::string unit;
  double scale;     // absolute tolerance = atol * scale
  OutputId output;  // every quadrature is also reported as an output
};

// Per-class structure of a unit holding a population: `n` classes, blocks of own states indexed by class
// (block b: states first[b] .. first[b] + n - 1) and blocks of per-class port fields. The framework colours the
// forward-AD Jacobian with it: a class row may read only its own class's variables, shared (scalar) variables
// and reductions; a scalar row reads class variables only through reductions (Ctx::reduce). Then every class
// block costs one AD direction, whatever n is.
struct ClassLayout {
  int n = 0;
  std::vector<StateId> state_blocks;
  std::vector<std::pair<PortId, int>> field_blocks;  // (port, first field)
  // The unit's pair processes (aggregation, breakage) couple every class with every other, slowly against each
  // class's own terms (drying, heat exchange): its Newton matrix is dense, and one without the couplings between
  // classes converges as fast. The automatic linear solver then takes the class-local one (class_local_solver.hpp)
  // from kClassLocalClasses classes on (solver_setup.cpp). A unit whose rates are the pair processes alone (a bare
  // population balance) leaves it false.
  bool class_local_newton = false;
};

class Settings;  // scene settings of one unit (flowsheet.hpp)
class Unit;

// What a unit declares.
class UnitSpec {
 public:
  StateId add_state(std::string name, StateKind kind, std::string unit, double scale);
  // A differential state that only integrates a flow for bookkeeping (no equation reads it; prefer a quadrature,
  // add_quadrature, unless the flow is a by-product of the residual that a quadrature would evaluate again).
  // A steady-state solve holds it and drops its equation.
  StateId add_accumulator(std::string name, std::string unit, double scale);
  // n consecutive states name_0 .. name_{n-1}; returns the first.
  StateId add_states(const std::string& name, int n, StateKind kind, const std::string& unit, double scale);
  // Inventories that cannot be negative: a run whose solution takes one below zero by more than the solver's
  // tolerance stops with a SolverError naming it (a rate that is not positivity-preserving there) instead of
  // returning it. `enforce` false: checked only, not constrained by the integrator (a unit whose scheme keeps it
  // non-negative by construction and that is held to exact conservation, which constraint handling gives up).
  void set_nonnegative(StateId first, int n = 1, bool enforce = true);
  ParamId add_param(ParamSpec spec);
  PortId add_port(std::string name, StreamKind kind, PortDir dir, int classes = 0, bool optional = false);
  // Declares the size grid (pivot diameters, m) a per-class port refers to.
  void set_port_grid(PortId port, std::vector<double> diameters);
  // Makes own state `state` the provider of field `field` of port `port`.
  void provide(PortId port, int field, StateId state);
  // Provides fields [0, n) of `port` by consecutive own states starting at `first_state`.
  void provide_all(PortId port, StateId first_state);
  // Field `field` of out/probe port `port` is the same variable as field `in_field` of in port `in_port` (a
  // pass-through: the chamber's outlet flow is its inlet flow), so no copy state and no copy equation.
  void forward(PortId port, int field, PortId in_port, int in_field);
  OutputId add_output(std::string name, std::string unit, OutputRole role = OutputRole::kValue,
                      std::string quantity = "", int cls = -1);
  // The size distribution of n classes as outputs psd_d_i (pivot diameter, m) then psd_m_i (class mass, kg), with
  // their roles; returns the ids of psd_d_0 and psd_m_0 (class i is at + i). `diameter_edges` (m, n + 1), when
  // given, let calibration read Q3 at any size from the class masses (size_edges()).
  std::pair<OutputId, OutputId> add_size_distribution(int n, std::vector<double> diameter_edges = {});
  const std::vector<double>& size_edges() const { return size_edges_; }
  // A quantity integrated by the solver's quadrature rule (IDAS quadratures): dQ/dt = Unit::quadrature(). It is
  // not an unknown of the Newton system; it is reported as an output of the same name, unit and role.
  QuadId add_quadrature(std::string name, std::string unit, double scale, OutputRole role = OutputRole::kValue,
                        std::string quantity = "");
  ReductionId add_reduction(std::string name);
  void set_classes(ClassLayout layout);
  // Declares the unit explicit: zero hold-up, every state algebraic with residual exactly x_k - f_k(ports),
  // f independent of the unit's own states. The simulator then evaluates f inline instead of integrating the
  // states, and chains its Jacobian into the consumers' (Schur complement), so such a unit adds no unknowns.
  void set_explicit() { explicit_ = true; }
  bool is_explicit() const { return explicit_; }
  // The unit adds part of its Jacobian itself (Unit::analytic_jacobian); during the framework's AD sweeps,
  // Ctx::in_jacobian() is true and eval() skips the terms that part covers. With `complete`, the analytic part is
  // the whole Jacobian (cj terms included) and no AD runs: kept only where a benchmark shows it pays, and tested
  // against AD.
  void set_analytic_part(bool complete = false) {
    analytic_part_ = true;
    analytic_complete_ = complete;
  }
  bool has_analytic_part() const { return analytic_part_; }
  bool analytic_complete() const { return analytic_complete_; }
  // The unit reads the parameters of the particle system `unit` (Ctx::shared): product properties and the size
  // grid are declared once per flowsheet.
  void use_shared_params(std::string unit) { shared_ = std::move(unit); }
  const std::string& shared_params() const { return shared_; }
  // The unit preconditions its own block for the iterative linear solver (Unit::precondition_setup/solve);
  // `solver.linear_solver: auto` picks that solver for a system past dense_limit that holds such a unit.
  void set_preconditioner() { preconditioner_ = true; }
  bool has_preconditioner() const { return preconditioner_; }
  // A zero-hold-up unit that comes with this one: the valve of an outlet whose flows are explicit in the unit's
  // hold-up (r M_i). Declared explicit, it is evaluated inline, so those flows are no unknowns of the Newton system;
  // as states of the unit itself they would double a particle unit's share of it. The flowsheet adds it right after
  // its owner as "<owner>:<name>", connects the owner's port `from` to its port "in", and takes the owner's port
  // name `as` in connections for its port "out". `make` receives the owner's instance name.
  struct Companion {
    std::string name;
    std::function<std::unique_ptr<Unit>(const std::string& owner)> make;
    PortId from;
    std::string as;
  };
  void add_companion(Companion c) { companions_.push_back(std::move(c)); }
  const std::vector<Companion>& companions() const { return companions_; }

  const std::vector<StateSpec>& states() const { return states_; }
  const std::vector<ParamSpec>& params() const { return params_; }
  const std::vector<PortSpec>& ports() const { return ports_; }
  const std::vector<OutputSpec>& outputs() const { return outputs_; }
  const std::vector<QuadSpec>& quadratures() const { return quads_; }
  const std::vector<std::string>& reductions() const { return reductions_; }
  const ClassLayout& classes() const { return classes_; }
  int state_index(const std::string& name) const;  // -1 if absent
  int param_index(const std::string& name) const;  // -1 if absent
  // A new default for parameter `index` with where it comes from (a material of the catalogue, materials.hpp).
  void rebase_param(int index, double value, std::string source);

 private:
  std::vector<StateSpec> states_;
  std::unordered_map<std::string, int> state_at_;  // name -> index: a 2-D population declares 10^4 states
  std::vector<ParamSpec> params_;
  std::vector<PortSpec> ports_;
  std::vector<OutputSpec> outputs_;
  std::vector<double> size_edges_;  // m, of the size distribution's classes (empty: not declared)
  std::vector<QuadSpec> quads_;
  std::vector<std::string> reductions_;
  ClassLayout classes_;
  std::vector<Companion> companions_;
  std::string shared_;
  bool explicit_ = false;
  bool preconditioner_ = false;
  bool analytic_part_ = false;
  bool analytic_complete_ = false;
};

// Everything one run of a unit computes and caches (tables from parameters, work arrays of the residual). The
// simulator makes one per unit and run (Unit::workspace), so runs never share mutable state.
struct Workspace {
  virtual ~Workspace() = default;
};

// Bookkeeping of the framework's coloured AD sweeps (dae_system.cpp): how a reduction's terms enter.
class ReductionRecorder {
 public:
  virtual ~ReductionRecorder() = default;
  virtual void term(ReductionId r, int cls, const Jet& value) = 0;
  // The Jet that stands for the finished sum in this sweep: its value, and a seed if the sweep carries its direction.
  virtual Jet result(ReductionId r, double value) = 0;
};

// The view of the global system a unit's residual sees.
template <class T>
struct Ctx {
  double t;
  const T* y;   // global states
  const T* yp;  // global state derivatives
  const T* p;   // this unit's parameters (value at time t for inputs)
  T* r;         // this unit's residual rows (or output values in report, quadrature rates in quadrature)
  int offset;   // global index of own state 0
  const std::vector<std::vector<int>>* port_index;  // per port, per field: global state index
  double t_seg = 0.0;                               // start of the current integration segment (between breakpoints)
  Workspace* work = nullptr;                        // this run's workspace of the unit
  const T* shared = nullptr;  // parameters of the particle system the unit reads (UnitSpec::use_shared_params)
  const T* quad = nullptr;    // this unit's quadratures (report only)
  ReductionRecorder* recorder = nullptr;                     // set in the framework's coloured Jacobian sweeps only
  const std::vector<std::vector<int>>* port_runs = nullptr;  // UnitInstance::port_runs, where the framework sets it

  const T& x(StateId k) const { return y[offset + k.i]; }
  const T& xd(StateId k) const { return yp[offset + k.i]; }
  const T& par(ParamId k) const { return p[k.i]; }
  const T& sh(ParamId k) const { return shared[k.i]; }
  const T& q(QuadId k) const { return quad[k.i]; }
  T& res(StateId k) const { return r[k.i]; }
  T& out(OutputId k) const { return r[k.i]; }
  // A field of an optional port left unconnected reads as zero.
  const T& port(PortId p, int field) const {
    const int i = (*port_index)[p.i][field];
    return i >= 0 ? y[i] : zero();
  }
  // Fields first .. first + count - 1 of port p as one array when their states are consecutive (a block of the unit
  // that provides them), else nullptr: loops over a stream's classes then read it directly, and vectorize.
  const T* port_block(PortId p, int first, int count) const {
    if (!port_runs || (*port_runs)[p.i][first] < count) return nullptr;
    return y + (*port_index)[p.i][first];
  }
  // The same fields as an array always: port_block where they are consecutive, else gathered into `scratch` (an
  // unconnected optional field reads zero), so that a unit writes its class loops once.
  const T* port_array(PortId p, int first, int count, std::vector<T>& scratch) const {
    if (const T* block = port_block(p, first, count)) return block;
    scratch.resize(count);
    for (int k = 0; k < count; ++k) scratch[k] = port(p, first + k);
    return scratch.data();
  }
  bool connected(PortId p) const {
    for (int i : (*port_index)[p.i])
      if (i < 0) return false;
    return true;
  }
  // True during the framework's AD sweeps of a unit with an analytic part: eval() leaves out the terms that
  // Unit::analytic_jacobian() differentiates.
  bool in_jacobian() const { return recorder != nullptr; }
  // The sum over classes sum_i term(i), where term(i) reads only class i's variables, shared variables and
  // earlier reductions. Called once per evaluation for each declared reduction, in declaration order.
  template <class F>
  T reduce(ReductionId r, int n, F&& term) const {
    T sum(0.0);
    if constexpr (std::is_same_v<T, Jet>) {
      if (recorder) {
        for (int i = 0; i < n; ++i) {
          const T v = term(i);
          recorder->term(r, i, v);
          sum += v;
        }
        return recorder->result(r, sum.a);
      }
    }
    for (int i = 0; i < n; ++i) sum += term(i);
    return sum;
  }
  template <class W>
  W& ws() const {
    return static_cast<W&>(*work);
  }
  static const T& zero() {
    static const T z(0.0);
    return z;
  }
};

// Initial values of own states (differential: the initial condition; algebraic: a guess that consistent
// initialization corrects) and quadratures (usually zero). Written as a template so sensitivities of initial
// states to parameters are exact.
template <class T>
struct InitCtx {
  const T* p;
  T* x0;                      // own states
  const T* shared = nullptr;  // parameters of the particle system
  Workspace* work = nullptr;
  const T& par(ParamId k) const { return p[k.i]; }
  const T& sh(ParamId k) const { return shared[k.i]; }
  T& x(StateId k) const { return x0[k.i]; }
};

// Receives analytic Jacobian entries dF_row/dx_col + cj dF_row/dxdot_col (row local, col global).
// A unit's Jacobian has O(N^2) entries for N size classes, so the dense case is an inline store, not a virtual
// call per entry; other sinks (sparse storage) take the virtual path.
class JacobianSink {
 public:
  virtual ~JacobianSink() = default;
  void add(int local_row, int global_col, double value) {
    if (dense_)
      dense_[size_t(global_col) * ld_ + size_t(local_row)] += value;
    else
      add_entry(local_row, global_col, value);
  }
  // The outer product u w^T on local rows 0..n_rows-1 and the global columns `cols`: how rows that all depend on
  // one shared intermediate (a sum over classes) enter. A sink that can keep the product factored does (the
  // Schur complement of inlined units); the default expands it entry by entry.
  virtual void add_outer(int n_rows, const double* u, int n_cols, const int* cols, const double* w) {
    for (int r = 0; r < n_rows; ++r)
      if (u[r] != 0.0)
        for (int k = 0; k < n_cols; ++k)
          if (w[k] != 0.0) add(r, cols[k], u[r] * w[k]);
  }
  // The unit's rows of global column `col` in dense storage (add(r, col, v) adds v to element r), or nullptr when
  // the sink is not dense: for units that add whole columns at a time.
  double* dense_column(int global_col) const { return dense_ ? dense_ + size_t(global_col) * ld_ : nullptr; }
  // True when the Jacobian feeds a class-local Newton matrix (class_local_solver.hpp), which reads only the entries
  // within one size class and those of the states that are not per class: a unit may then leave out the entries
  // between two different classes of its populations (they would be ignored), and skip what they cost.
  bool classes_local() const { return classes_local_; }
  void set_classes_local(bool on) { classes_local_ = on; }
  // What such a unit left out, for the conservation of its class state blocks (ClassLayout::class_local_newton):
  // `value` is the sum, over the rows of the block that holds local row `row`, of the entries of global column `col`
  // it did not form. The pair processes move mass and water between classes and never make or lose any, so their
  // entries in a column sum to zero over a block; what a unit leaves out is minus what it kept. The solver adds these
  // sums back as one outer product per block, and its Newton corrections conserve the block's total as the exact
  // matrix's do.
  virtual void left_out(int /*row*/, int /*col*/, double /*value*/) {}

 protected:
  JacobianSink() = default;
  // Dense column-major storage with leading dimension `ld`, `unit_rows` pointing at the unit's first row.
  JacobianSink(double* unit_rows, size_t ld) : dense_(unit_rows), ld_(ld) {}
  virtual void add_entry(int /*local_row*/, int /*global_col*/, double /*value*/) {}

 private:
  double* dense_ = nullptr;
  size_t ld_ = 0;
  bool classes_local_ = false;
};

class Unit {
 public:
  virtual ~Unit() = default;
  virtual std::string type() const = 0;
  // Declares states, params, ports and outputs; settings shape the structure.
  virtual void declare(UnitSpec& spec, Settings& settings) = 0;
  // The run's workspace (work arrays sized once, caches); units without any keep the default.
  virtual std::unique_ptr<Workspace> workspace() const { return std::make_unique<Workspace>(); }
  // Called before each run with current parameter values (at t = 0) and the particle system's: precompute into
  // the workspace what does not change with the state. Throws ConfigError for combinations the bounds cannot catch.
  virtual void configure(const UnitSpec& /*spec*/, const double* /*params*/, const double* /*shared*/,
                         Workspace& /*w*/) const {}
  // Cheap checks across parameters (t_off >= t_on) that the bounds alone cannot catch; called before every
  // configure() and when a scene is loaded. Throws ConfigError relative to the unit ("t_off = 600 s: ...").
  virtual void check(const UnitSpec& /*spec*/, const double* /*params*/) const {}

  virtual Status residual(const Ctx<double>& c) const = 0;
  virtual Status residual(const Ctx<Jet>& c) const = 0;
  virtual void initial(InitCtx<double>& c) const = 0;
  virtual void initial(InitCtx<Jet>& c) const = 0;
  // The part of the Jacobian the unit supplies itself (UnitSpec::set_analytic_part), dF/dy + cj dF/dy', added to
  // the AD part.
  virtual void analytic_jacobian(const Ctx<double>& /*c*/, double /*cj*/, JacobianSink& /*sink*/) const {}
  // Iterative linear solver (solver.linear_solver: gmres; UnitSpec::set_preconditioner): an approximation P of the
  // unit's own block of dF/dx + cj dF/dx' (its rows, the columns of its own states), built at the state in `c` and
  // kept in the run's workspace (c.work); precondition_solve writes z = P^-1 r over the unit's own states. P need
  // not be exact (GMRES corrects it), only cheap to apply and close enough that few iterations are needed.
  virtual void precondition_setup(const Ctx<double>& /*c*/, double /*cj*/) const {}
  virtual void precondition_solve(const Ctx<double>& /*c*/, double /*cj*/, const double* r, double* z) const {
    (void)r, (void)z;
  }
  // Times where the unit's equations change discontinuously (spray start/stop) for the current parameters;
  // the simulator stops and re-initializes there. Inside eval(), use Ctx::t_seg (the start of the current
  // segment) to decide which side of such a time the solver is on.
  virtual std::vector<double> breakpoints(const double* /*params*/) const { return {}; }
  // Each state's scale for this run (absolute tolerance = atol * scale), `scales` arriving filled with the declared
  // ones: a unit whose states span orders of magnitude in what they carry (particle numbers of classes whose
  // volumes differ by 10^9) weights them here with its parameters.
  virtual void tolerance_scales(const double* /*params*/, const double* /*shared*/, double* /*scales*/) const {}
  // Reported outputs (declared with add_output), written to c.out(); for Jets, their sensitivities.
  virtual void report(const Ctx<double>& /*c*/) const {}
  virtual void report(const Ctx<Jet>& /*c*/) const {}
  // Rates of the quadratures, written to c.r[k] for QuadId k.
  virtual void quadrature(const Ctx<double>& /*c*/) const {}
  virtual void quadrature(const Ctx<Jet>& /*c*/) const {}
};

namespace detail {
template <class D, class = void>
struct HasOutputs : std::false_type {};
template <class D>
struct HasOutputs<D, std::void_t<decltype(&D::template outputs<double>)>> : std::true_type {};
template <class D, class = void>
struct HasQuad : std::false_type {};
template <class D>
struct HasQuad<D, std::void_t<decltype(&D::template quad<double>)>> : std::true_type {};
}  // namespace detail

// Instantiates the residual, initial values, outputs and quadratures for double and Jet from the derived unit's
// templates
//   template <class T> Status eval(const Ctx<T>&) const;    template <class T> void init(InitCtx<T>&) const;
//   template <class T> void outputs(const Ctx<T>&) const;   (optional)
//   template <class T> void quad(const Ctx<T>&) const;      (optional)
template <class Derived>
class UnitBase : public Unit {
 public:
  Status residual(const Ctx<double>& c) const override { return self().eval(c); }
  Status residual(const Ctx<Jet>& c) const override { return self().eval(c); }
  void initial(InitCtx<double>& c) const override { self().init(c); }
  void initial(InitCtx<Jet>& c) const override { self().init(c); }
  void report(const Ctx<double>& c) const override {
    if constexpr (detail::HasOutputs<Derived>::value) self().outputs(c);
  }
  void report(const Ctx<Jet>& c) const override {
    if constexpr (detail::HasOutputs<Derived>::value) self().outputs(c);
  }
  void quadrature(const Ctx<double>& c) const override {
    if constexpr (detail::HasQuad<Derived>::value) self().quad(c);
  }
  void quadrature(const Ctx<Jet>& c) const override {
    if constexpr (detail::HasQuad<Derived>::value) self().quad(c);
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace granuflow
