// The unit-model interface.
//
// A unit declares, once, its states (differential or algebraic, SI unit, typical scale), its parameters
// (ParamSpec), its ports and its reported outputs (declare). Its residual is written once as a template on the
// scalar type T:
//
//     F_k(t, x, xdot, p) = 0   for every own state k (one equation per state, written to res(k)),
//
// where x holds the unit's own states and, through its ports, the fields provided by connected units. The
// framework owns the solver: Jacobians (forward AD over the unit's local variables, or an analytic Jacobian
// the unit supplies), sparsity, linear solves, consistent initialization and input breakpoints.
// Contract: eval() writes every res(k) for k < number of own states; it returns Status::kRecoverable to make
// the integrator cut the step (e.g. a mass went negative), kFatal to stop.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/ad.hpp"
#include "granuflow/param.hpp"
#include "granuflow/stream.hpp"

namespace granuflow {

// A differential state k has the residual y'_k - f(y, p, t) (no other dependence on y'): the simulator relies on it to
// reuse Jacobians across steps, and checks it on the first evaluation of each run (falling back to fresh ones).
enum class StateKind { Differential, Algebraic };
enum class Status { kOk = 0, kRecoverable = 1, kFatal = -1 };

struct StateSpec {
  std::string name;
  StateKind kind;
  std::string unit;
  double scale;  // typical magnitude: absolute tolerance = atol * scale
};

struct PortSpec {
  std::string name;
  StreamKind kind;
  PortDir dir;
  int classes = 0;            // solids: number of size classes
  bool optional = false;      // may stay unconnected: its read fields are then zero (a mechanism left out)
  std::vector<double> grid;   // per-class streams: pivot diameters (m); connected ports must agree
  std::vector<int> provided;  // per field: own state index providing it, or -1 (read from the peer)
};

struct OutputSpec {
  std::string name;
  std::string unit;
};

class Settings;  // scene settings of one unit (flowsheet.hpp)

// What a unit declares. Indices returned are the unit's local indices used in eval().
class UnitSpec {
 public:
  int add_state(std::string name, StateKind kind, std::string unit, double scale);
  int add_param(ParamSpec spec);
  int add_port(std::string name, StreamKind kind, PortDir dir, int classes = 0, bool optional = false);
  // Declares the size grid (pivot diameters, m) a per-class port refers to.
  void set_port_grid(int port, std::vector<double> diameters);
  // Makes own state `state` the provider of field `field` of port `port`.
  void provide(int port, int field, int state);
  // Provides fields [0, n) of `port` by consecutive own states starting at `first_state`.
  void provide_all(int port, int first_state);
  int add_output(std::string name, std::string unit);
  // Declares the unit explicit: zero hold-up, every state algebraic with residual exactly x_k - f_k(ports),
  // f independent of the unit's own states. The simulator then evaluates f inline instead of integrating the
  // states, and chains its Jacobian into the consumers' (Schur complement), so such a unit adds no unknowns.
  void set_explicit() { explicit_ = true; }
  bool is_explicit() const { return explicit_; }

  const std::vector<StateSpec>& states() const { return states_; }
  const std::vector<ParamSpec>& params() const { return params_; }
  const std::vector<PortSpec>& ports() const { return ports_; }
  const std::vector<OutputSpec>& outputs() const { return outputs_; }
  int state_index(const std::string& name) const;  // -1 if absent
  int param_index(const std::string& name) const;  // -1 if absent

 private:
  std::vector<StateSpec> states_;
  std::vector<ParamSpec> params_;
  std::vector<PortSpec> ports_;
  std::vector<OutputSpec> outputs_;
  bool explicit_ = false;
};

// The view of the global system a unit's residual sees.
template <class T>
struct Ctx {
  double t;
  const T* x;                                       // global states
  const T* xdot;                                    // global state derivatives
  const T* p;                                       // this unit's parameters (value at time t for inputs)
  T* r;                                             // this unit's residual rows
  int offset;                                       // global index of own state 0
  const std::vector<std::vector<int>>* port_index;  // per port, per field: global state index
  double t_seg = 0.0;                               // start of the current integration segment (between breakpoints)

  const T& x_(int k) const { return x[offset + k]; }
  const T& xd(int k) const { return xdot[offset + k]; }
  const T& par(int k) const { return p[k]; }
  // A field of an optional port left unconnected reads as zero.
  const T& port(int port_id, int field) const {
    const int i = (*port_index)[port_id][field];
    return i >= 0 ? x[i] : zero();
  }
  const T& port_dot(int port_id, int field) const {
    const int i = (*port_index)[port_id][field];
    return i >= 0 ? xdot[i] : zero();
  }
  bool connected(int port_id) const {
    for (int i : (*port_index)[port_id])
      if (i < 0) return false;
    return true;
  }
  static const T& zero() {
    static const T z(0.0);
    return z;
  }
  T& res(int k) const { return r[k]; }
};

// Initial values of own states (differential: the initial condition; algebraic: a guess that consistent
// initialization corrects). Written as a template so sensitivities of initial states to parameters are exact.
template <class T>
struct InitCtx {
  const T* p;
  T* x0;  // own states
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
        for (int k = 0; k < n_cols; ++k) add(r, cols[k], u[r] * w[k]);
  }

 protected:
  JacobianSink() = default;
  // Dense column-major storage with leading dimension `ld`, `unit_rows` pointing at the unit's first row.
  JacobianSink(double* unit_rows, size_t ld) : dense_(unit_rows), ld_(ld) {}
  virtual void add_entry(int /*local_row*/, int /*global_col*/, double /*value*/) {}

 private:
  double* dense_ = nullptr;
  size_t ld_ = 0;
};

class Unit {
 public:
  virtual ~Unit() = default;
  virtual std::string type() const = 0;
  // Declares states, params, ports and outputs; settings shape the structure.
  virtual void declare(UnitSpec& spec, Settings& settings) = 0;
  // Called before each run with current parameter values (at t = 0): precompute what does not change
  // with the state. Throws ConfigError for combinations the bounds alone cannot catch.
  virtual void configure(const UnitSpec& /*spec*/, const double* /*params*/) {}
  // Cheap checks across parameters (t_off >= t_on) that the bounds alone cannot catch; called before every
  // configure() and when a scene is loaded. Throws ConfigError relative to the unit ("t_off = 600 s: ...").
  virtual void check(const UnitSpec& /*spec*/, const double* /*params*/) const {}

  virtual Status residual(const Ctx<double>& c) const = 0;
  virtual Status residual(const Ctx<Jet>& c) const = 0;
  virtual void initial(InitCtx<double>& c) const = 0;
  virtual void initial(InitCtx<Jet>& c) const = 0;
  // Optional analytic Jacobian of the whole unit; returns false to let the framework use AD.
  virtual bool jacobian(const Ctx<double>& /*c*/, double /*cj*/, JacobianSink& /*sink*/) const { return false; }
  // Times where the unit's equations change discontinuously (spray start/stop) for the current parameters;
  // the simulator stops and re-initializes there. Inside eval(), use Ctx::t_seg (the start of the current
  // segment) to decide which side of such a time the solver is on.
  virtual std::vector<double> breakpoints(const double* /*params*/) const { return {}; }
  // Reported outputs (declared with add_output), evaluated at output times.
  virtual void report(const Ctx<double>& /*c*/, double* /*out*/) const {}
};

// Instantiates the residual and initial values for double and Jet from the derived unit's templates
//   template <class T> Status eval(const Ctx<T>&) const;   template <class T> void init(InitCtx<T>&) const;
template <class Derived>
class UnitBase : public Unit {
 public:
  Status residual(const Ctx<double>& c) const override { return self().eval(c); }
  Status residual(const Ctx<Jet>& c) const override { return self().eval(c); }
  void initial(InitCtx<double>& c) const override { self().init(c); }
  void initial(InitCtx<Jet>& c) const override { self().init(c); }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace granuflow
