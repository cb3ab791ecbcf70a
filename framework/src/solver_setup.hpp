// The SUNDIALS plumbing shared by dynamic runs (simulator.cpp) and steady-state solves (steady_state.cpp): RAII
// holders, the linear solver choice, IDA's residual and Jacobian callbacks with the Jacobian reuse cache, and one
// IDA integrator set up the same way everywhere.
#pragma once
#include <idas/idas.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <functional>
#include <string>
#include <vector>

#include "granuflow/dae_system.hpp"
#include "granuflow/simulator.hpp"
#include "jacobian_cache.hpp"
#include "serial_vector_ops.hpp"

namespace granuflow::detail {

struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};
struct NVec {
  N_Vector v = nullptr;
  // Optimized arithmetic (serial_vector_ops.hpp), which the integrators' clones of v inherit.
  NVec(int n, SUNContext ctx) : v(N_VNew_Serial(n, ctx)) {
    install_serial_vector_ops(v);
    N_VConst(0.0, v);
  }
  ~NVec() { N_VDestroy(v); }
  double* data() const { return N_VGetArrayPointer(v); }
};
struct Mat {
  SUNMatrix m = nullptr;
  ~Mat() {
    if (m) SUNMatDestroy(m);
  }
};
struct LinSol {
  SUNLinearSolver s = nullptr;
  ~LinSol() {
    if (s) SUNLinSolFree(s);
  }
};

// The linear solvers of the Newton iterations. Direct ones factor the exact Jacobian (dense or sparse); the
// iterative one (gmres) never forms it: GMRES (SUNDIALS SPGMR) on difference-quotient Jacobian-vector products of
// the residual, left-preconditioned by the units' blocks (DaeSystem::precondition_setup/solve). It is the only
// choice for units whose Jacobian is both large and dense (a 2-D population: every bin pair aggregates).
// kBanded: the dense Jacobian, factored as band + outer products + border (banded_lowrank_solver.hpp).
// kClassLocal: the dense Jacobian without the couplings between size classes, factored per class and border
// (class_local_solver.hpp): an approximate Newton matrix for populations whose pair processes couple every class.
enum class LinearSolverKind { kDense, kSparse, kGmres, kBanded, kClassLocal };
// kAuto: class_local for a population whose pair processes couple its classes (ClassLayout::class_local_newton) from
// kClassLocalClasses classes on, where the integrator has it (`structured_available`: IDAS) and no sensitivities are
// asked for; else dense up to dense_limit unknowns; beyond, gmres if a unit preconditions itself, else (IDAS) banded
// when size classes hold most unknowns, else use_dense().
LinearSolverKind choose_linear_solver(const Flowsheet& fs, LinearSolverChoice choice, int dense_limit,
                                      bool structured_available = true, bool sensitivities = false);
inline constexpr int kClassLocalClasses = 40;
const char* linear_solver_name(LinearSolverKind k);
// Dense: Eigen's blocked LU behind a SUNDenseMatrix (`structure` kBanded: the band + low-rank solver of
// banded_lowrank_solver.hpp on the same matrix, kClassLocal: class_local_solver.hpp's); sparse: KLU on the
// flowsheet's sparsity pattern.
void make_linear_solver(bool dense, const DaeSystem& sys, N_Vector y, SUNContext ctx, Mat& a, LinSol& ls,
                        LinearSolverKind structure = LinearSolverKind::kDense);
inline constexpr int kGmresMaxKrylov = 20;  // Krylov dimension (no restarts)
// SUNDIALS' name of a return flag from a *GetReturnFlagName call (which hands the string to the caller), or fallback.
std::string flag_name(char* name, const char* fallback);
std::string ida_flag_text(int flag);
void check(int flag, const char* call);  // throws on a negative SUNDIALS flag
// The flowsheet's sparsity pattern into a compressed-column SUNMatrix (column pointers and row indices; SUNDIALS
// lets a Jacobian callback rewrite them, and KLU reads them at every factorization).
void set_sparse_pattern(const SparsityPattern& pat, SUNMatrix J);

// State shared by the IDAS callbacks.
struct IdaUser {
  IdaUser(DaeSystem* s, bool d, std::vector<int> params = {}) : sys(s), dense(d), sens_params(std::move(params)) {}
  DaeSystem* sys;
  bool dense;
  std::vector<int> sens_params;
  std::string last_error;
  unsigned interrupt_calls = 0;  // interrupt_requested(calls)
  std::vector<const double*> yS, ypS;
  std::vector<double*> rS, qS;
  void* mem = nullptr;  // the IDA integrator, when Jacobians may be reused (simulate, dense)
  JacobianCache cache;
  bool fresh_only = false;  // consistent initialization: Newton from a guess needs the Jacobian of each iterate
  bool iterative = false;   // GMRES with the units' preconditioners instead of a factored Jacobian
  bool banded = false;      // dense Jacobian, band + low-rank factorization (LinearSolverKind::kBanded)
  SUNLinearSolver structured = nullptr;  // that solver, told when a kept Jacobian is reused
  bool class_local = false;              // dense Jacobian, class-local factorization (LinearSolverKind::kClassLocal)
  SUNLinearSolver local = nullptr;       // that solver, told to factor the whole matrix for consistent values
  std::function<int(double, const double*, const double*, double*)> roots;  // state events' g (events_run.hpp)
};
int ida_res(realtype t, N_Vector y, N_Vector yp, N_Vector r, void* ud);
int ida_jac(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
            N_Vector);
void ida_err(int code, const char* module, const char* function, char* msg, void* ud);
int ida_psetup(realtype t, N_Vector y, N_Vector yp, N_Vector r, realtype cj, void* ud);
int ida_psolve(realtype t, N_Vector y, N_Vector yp, N_Vector r, N_Vector rvec, N_Vector zvec, realtype cj,
               realtype delta, void* ud);

// One IDA integrator over a DaeSystem, set up the same way for simulation and for the consistent starting point
// of a steady-state solve: residual, tolerances, differential/algebraic ids, the linear solver and exact Jacobian.
struct Ida {
  void* mem = nullptr;
  Mat A;
  LinSol LS;
  IdaUser* user = nullptr;  // set with a matrix-based solver (dense: make_eigen_dense_solver's)
  Ida(SUNContext ctx, IdaUser& user, double t0, const NVec& y, const NVec& yp, double rtol, const NVec& atol);
  ~Ida() { IDAFree(&mem); }
  // From the size of the largest block the dense solver factored (call after a setup, e.g. after consistent
  // initialization): how far cj may move before IDA refactors the Newton matrix, and how many steps a cached
  // Jacobian is kept; see solver_setup.cpp.
  void tune_refactoring();
  void tune_refactoring(int block);  // for a largest factored block of `block` states
  Ida(const Ida&) = delete;
  Ida& operator=(const Ida&) = delete;
};

// Dense Jacobians whenever the system is small or mostly full; see solver_setup.cpp.
bool use_dense(const Flowsheet& fs, LinearSolverChoice choice, int dense_limit);

}  // namespace granuflow::detail
