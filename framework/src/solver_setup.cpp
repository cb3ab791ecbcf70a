#include "solver_setup.hpp"

#include <sunlinsol/sunlinsol_spgmr.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include "banded_lowrank_solver.hpp"
#include "class_local_solver.hpp"
#include "eigen_linear_solver.hpp"
#include "granuflow/interrupt.hpp"

namespace granuflow::detail {

// Dense: Eigen's blocked LU behind a SUNDenseMatrix; sparse: KLU on the flowsheet's sparsity pattern.
void make_linear_solver(bool dense, const DaeSystem& sys, N_Vector y, SUNContext ctx, Mat& a, LinSol& ls,
                        LinearSolverKind structure) {
  const int n = sys.size();
  if (dense) {
    a.m = SUNDenseMatrix(n, n, ctx);
    // DaeSystem::jacobian writes all n^2 entries, so IDA's zeroing before each evaluation is skipped.
    a.m->ops->zero = [](SUNMatrix) -> int { return 0; };
    ls.s = structure == LinearSolverKind::kBanded       ? make_banded_lowrank_solver(ctx, class_structure(sys))
           : structure == LinearSolverKind::kClassLocal ? make_class_local_solver(ctx, class_local_source(sys))
                                                        : make_eigen_dense_solver(ctx);
  } else {
    a.m = SUNSparseMatrix(n, n, sys.pattern().nnz(), CSC_MAT, ctx);
    ls.s = SUNLinSol_KLU(y, a.m, ctx);
  }
}

std::string flag_name(char* name, const char* fallback) {
  std::string s = name ? name : fallback;
  free(name);
  return s;
}

std::string ida_flag_text(int flag) { return flag_name(IDAGetReturnFlagName(flag), "IDA error"); }

void set_sparse_pattern(const SparsityPattern& pat, SUNMatrix J) {
  sunindextype* cp = SUNSparseMatrix_IndexPointers(J);
  sunindextype* ri = SUNSparseMatrix_IndexValues(J);
  for (int c = 0; c <= pat.n; ++c) cp[c] = pat.col_ptr[c];
  for (int k = 0; k < pat.nnz(); ++k) ri[k] = pat.row_idx[k];
}

void check(int flag, const char* call) {
  if (flag < 0) throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

int ida_res(realtype t, N_Vector y, N_Vector yp, N_Vector r, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  if (interrupt_requested(u->interrupt_calls)) return -1;  // the run then ends with Interrupted (simulator.cpp)
  try {
    return static_cast<int>(u->sys->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(r)));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

void check_contract(DaeSystem& sys, double t, const double* y, const double* yp, JacobianCache& k) {
  const int n = sys.size();
  const auto id = sys.differential_id();
  const auto scale = sys.scales();
  std::vector<double> v(n), yp1(yp, yp + n), r0(n), r1(n);
  for (int i = 0; i < n; ++i) {  // golden-ratio sequence in [0.5, 1.5): no two components alike, none zero
    const double u = 0.5 + std::fmod(0.6180339887498949 * (i + 1), 1.0);
    v[i] = u * scale[i];
    yp1[i] += v[i];
  }
  k.reusable =
      sys.residual(t, y, yp, r0.data()) == Status::kOk && sys.residual(t, y, yp1.data(), r1.data()) == Status::kOk;
  for (int i = 0; i < n && k.reusable; ++i) {
    const double d = r1[i] - r0[i], expect = id[i] == 1.0 ? v[i] : 0.0;
    // round-off of y'_k + v_k - f_k against y'_k - f_k
    if (std::abs(d - expect) > 1e-12 * (std::abs(r0[i]) + std::abs(r1[i]) + std::abs(yp1[i]) + std::abs(v[i])))
      k.reusable = 0;
  }
  k.differential.clear();
  for (int i = 0; i < n; ++i)
    if (id[i] == 1.0) k.differential.push_back(i);
}

void JacobianCache::keep(const double* a, int n, double cj_at, long step_at, long fails_at) {
  held = a;
  diag.resize(differential.size());
  for (size_t d = 0; d < differential.size(); ++d) diag[d] = a[size_t(differential[d]) * n + differential[d]];
  cj = cj_at;
  step = step_at;
  conv_fails = fails_at;
  valid = true;
}

int ida_jac(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
            N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
  if (interrupt_requested(u->interrupt_calls)) return -1;  // a Jacobian of a large flowsheet can take a second
  try {
    if (u->dense) {
      double* a = SUNDenseMatrix_Data(J);
      const int n = u->sys->size();
      JacobianCache& k = u->cache;
      long step = 0, fails = 0;
      if (u->mem) {
        IDAGetNumSteps(u->mem, &step);
        IDAGetNumNonlinSolvConvFails(u->mem, &fails);
        long sens_fails = 0;  // the staggered sensitivity corrector shares the Newton matrix
        if (!u->sens_params.empty() && IDAGetSensNumNonlinSolvConvFails(u->mem, &sens_fails) == IDA_SUCCESS)
          fails += sens_fails;
      }
      if (u->mem && !u->fresh_only && k.valid && k.reusable == 1 && fails == k.conv_fails &&
          step - k.step < k.max_age && k.held == a) {
        for (size_t d = 0; d < k.differential.size(); ++d) {
          const int i = k.differential[d];
          a[size_t(i) * n + i] = k.diag[d] + (cj - k.cj);
        }
        if (u->structured) banded_lowrank_same_but_diagonal(u->structured);
        if (u->local) class_local_same_but_diagonal(u->local);
        return 0;
      }
      k.held = nullptr;  // overwritten below; kept again if reusable
      // A class-local Newton matrix does not read the couplings between classes: the units may skip them, except
      // while consistent values are computed (the solver factors the whole matrix then).
      {
        struct Local {  // on for this evaluation only, also when it throws
          DaeSystem& sys;
          ~Local() { sys.set_classes_local(false); }
        } local{*u->sys};
        u->sys->set_classes_local(u->class_local && !u->fresh_only);
        u->sys->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, a, nullptr);
      }
      if (!u->mem) return 0;
      if (k.reusable < 0) check_contract(*u->sys, t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), k);
      if (k.reusable == 1) k.keep(a, n, cj, step, fails);
    } else {
      set_sparse_pattern(u->sys->pattern(), J);
      u->sys->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, nullptr, SUNSparseMatrix_Data(J));
    }
    return 0;
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_psetup(realtype t, N_Vector y, N_Vector yp, N_Vector, realtype cj, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    u->sys->precondition_setup(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj);
    return 0;
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_psolve(realtype t, N_Vector y, N_Vector yp, N_Vector, N_Vector rvec, N_Vector zvec, realtype cj, realtype,
               void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    u->sys->precondition_solve(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, N_VGetArrayPointer(rvec),
                               N_VGetArrayPointer(zvec));
    return 0;
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

void ida_err(int code, const char* module, const char* function, char* msg, void* ud) {
  if (code >= 0) return;  // warnings are not errors
  auto* u = static_cast<IdaUser*>(ud);
  u->last_error = std::string(module) + "." + function + ": " + msg;
}

Ida::Ida(SUNContext ctx, IdaUser& user, double t0, const NVec& y, const NVec& yp, double rtol, const NVec& atol) {
  DaeSystem& sys = *user.sys;
  const int n = sys.size();
  mem = IDACreate(ctx);
  check(IDAInit(mem, ida_res, t0, y.v, yp.v), "IDAInit");
  check(IDASVtolerances(mem, rtol, atol.v), "IDASVtolerances");
  check(IDASetUserData(mem, &user), "IDASetUserData");
  check(IDASetErrHandlerFn(mem, ida_err, &user), "IDASetErrHandlerFn");
  NVec id(n, ctx);
  const auto ids = sys.differential_id();
  std::copy(ids.begin(), ids.end(), id.data());
  check(IDASetId(mem, id.v), "IDASetId");
  if (user.iterative) {
    LS.s = SUNLinSol_SPGMR(y.v, SUN_PREC_LEFT, kGmresMaxKrylov, ctx);
    check(IDASetLinearSolver(mem, LS.s, nullptr), "IDASetLinearSolver");
    check(IDASetPreconditioner(mem, ida_psetup, ida_psolve), "IDASetPreconditioner");
    return;
  }
  make_linear_solver(user.dense, sys, y.v, ctx, A, LS,
                     user.banded        ? LinearSolverKind::kBanded
                     : user.class_local ? LinearSolverKind::kClassLocal
                                        : LinearSolverKind::kDense);
  this->user = &user;
  if (user.banded) user.structured = LS.s;
  if (user.class_local) user.local = LS.s;
  check(IDASetLinearSolver(mem, LS.s, A.m), "IDASetLinearSolver");
  check(IDASetJacFn(mem, ida_jac), "IDASetJacFn");
}

// IDA refactors the Newton matrix cF_y' + F_y when cj = alpha_0 / h has moved by more than 25 % since the last
// factorization (its default) and otherwise rescales the Newton correction for the stale cj. With the Jacobian cached
// (ida_jac), such a setup is an LU and nothing else. Past about a hundred states in one block that LU costs more than
// the extra Newton iterations of a stale cj, so large blocks wait for a 50 % change. Measured with
// granuflow_run_scene, best of 3 (wall ms, default -> 50 %): sieve-mill loop for 300 h at 50, 100 and 200 classes
// (102, 202, 402 unknowns) 47.5 -> 45.0, 200 -> 166, 1127 -> 868; two-zone layering (a block of 400) 225 -> 161;
// free hold-up loop 82.7 -> 75.3. Smaller blocks keep the default: the headline scene at 40 classes (89 unknowns)
// was 4 % slower at 50 %, the tanks-in-series scene (blocks of at most 22 states) 38 % slower.
//
// A cached Jacobian is re-evaluated after 20 steps, or after 51 (CVODE's default) once the block reaches 64 states:
// there a Jacobian costs tens of residuals (the headline scene at 40 classes: 0.3 ms against 9 us), and a fresher
// one saves fewer Newton iterations than it costs. Measured the same way (wall ms, age 20 -> 51): headline scene at
// 40 classes 10.6 -> 9.7, 40 classes without breakage 11.1 -> 10.4, 100 classes 46.8 -> 42.9; sieve-mill loop
// 102 -> 98; free hold-up loop 58.5 -> 57.5; two-zone 85.6 -> 84.7. Below that size the headline scene at 10 and
// 20 classes (29 and 49 unknowns) was 1-6 % slower at 51, tanks in series 13 % slower: they keep 20.
//
// A large block also gets a tighter Newton test (0.2 of the error test's tolerance instead of IDAS's 0.33). With
// its matrix kept that long, Newton converges linearly and leaves up to a third of the tolerance in the solution;
// the local error estimate sees that as noise and the step stops growing, and at a constant step IDAS asks for no
// new matrix (it does so when cj moves or Newton fails), so nothing refreshes it: the free hold-up loop at 250 kg/h
// and a 1.7 mm cut, 100 classes, crept to its steady state at h = 174 s, 13323 steps over 600 h. With the tighter
// test a stale matrix fails, is evaluated again, and the step grows (1209 steps). Wall ms, 0.33 -> 0.2: sieve-mill
// loop for 300 h at 100 and 200 classes 59.8 -> 57.9, 206 -> 189 (50 classes, a block of 53, keeps 0.33);
// free hold-up loop 42.7 -> 39.0; two-zone layering 34.1 -> 36.9 (more Jacobians of its 308 unknowns).
constexpr int kLargeBlock = 100, kCostlyJacobian = 64;
constexpr double kLargeBlockNewtonTest = 0.2;
void Ida::tune_refactoring() {
  // The band + low-rank and the class-local solvers factor the whole matrix, cheaply: tuned as a block of that size.
  if (user && user->dense)
    tune_refactoring(is_banded_lowrank_solver(LS.s) ? banded_lowrank_stats(LS.s).states
                     : is_class_local_solver(LS.s)  ? class_local_stats(LS.s).states
                                                    : eigen_dense_largest_block(LS.s));
}

//
// A class-local setup (class_local_solver.hpp) costs a few residuals: refactoring at every change of cj keeps the
// approximate Newton matrix at the step's own cj, which saves more iterations than the setups cost. Headline scene
// at 80 classes, solve ms (cj change that refactors: 0.5 -> 0.25 -> 0.1 -> any): 12.1 -> 11.0 -> 9.8 -> 9.7 (460,
// 424, 341, 323 residuals; 18, 28, 35, 54 setups, 6-8 Jacobians).
constexpr double kClassLocalDeltaCj = 0.0;
void Ida::tune_refactoring(int block) {
  if (!user || !user->dense) return;
  check(IDASetDeltaCjLSetup(mem, user->class_local      ? kClassLocalDeltaCj
                                 : block >= kLargeBlock ? 0.5
                                                        : 0.25),
        "IDASetDeltaCjLSetup");
  check(IDASetNonlinConvCoef(mem, block >= kLargeBlock ? kLargeBlockNewtonTest : 0.33), "IDASetNonlinConvCoef");
  user->cache.max_age = block >= kCostlyJacobian ? 51 : 20;
}

// Dense Jacobians (explicit units inlined) up to `dense_limit` unknowns, and beyond that while the Jacobian is
// mostly full anyway (aggregation couples every size class with every other): at 200 classes the headline
// scene took 4.9 s with KLU on its 1034 states (60 % full) and 0.24 s dense on 429 unknowns with the spray
// zone inlined. Past kDenseMax unknowns the dense matrix itself is the problem.
constexpr int kDenseMax = 3000;
constexpr double kDenseFill = 0.25;
constexpr double kBandedShare = 0.5;
bool use_dense(const Flowsheet& fs, LinearSolverChoice choice, int dense_limit) {
  if (choice != LinearSolverChoice::kAuto) return choice == LinearSolverChoice::kDense;
  const int n = fs.n_states() - fs.n_explicit_states();
  if (n <= dense_limit) return true;
  if (n > kDenseMax) return false;
  return DaeSystem(fs, false).fill() >= kDenseFill;
}

}  // namespace granuflow::detail

namespace granuflow::detail {

namespace {
// The share of the unknowns (explicit units inlined) that size-class populations hold, per class: what the band +
// low-rank solver orders by class; the rest is its dense border.
double class_share(const Flowsheet& fs) {
  long in_classes = 0;
  for (const auto& u : fs.units()) {
    const ClassLayout& layout = u.spec.classes();
    if (!u.spec.is_explicit() && layout.n > 0) in_classes += long(layout.n) * long(layout.state_blocks.size());
  }
  return double(in_classes) / std::max(1, fs.n_states() - fs.n_explicit_states());
}
}  // namespace

// Past dense_limit, size-class populations go to the band + low-rank solver, which factors a setup densely where the
// matrix is not of that form (aggregation): KLU filled in on them (the tank chains at 60 classes, 3297 unknowns
// uninlined: 7.9 s against 0.31 s banded on 1134), and dense LU was twice the banded solve for two zones at 200
// classes (0.23 against 0.115 s).
//
// A population whose pair processes couple every class with every other, slowly against each class's own terms
// (ClassLayout::class_local_newton), goes to the class-local solver from kClassLocalClasses classes on: its Newton
// matrix is dense, and the dense LU and the pair Jacobian grow as the cube and the square of the classes. Headline
// scene, solve only, median of 7 pinned to one vCPU (ms, dense -> class_local): 10 classes 2.13 -> 1.85, 20 classes
// 3.36 -> 2.51, 40 classes 6.24 -> 4.49, 80 classes 18.5 -> 9.4, 193 classes 106 -> 47. The coarse grids gain
// least, and there the exact matrix keeps the paper's 10-class grid, on which its kinetics were fitted, and every
// result computed on such grids to the bit; `linear_solver: class_local` asks for it on any grid.
LinearSolverKind choose_linear_solver(const Flowsheet& fs, LinearSolverChoice choice, int dense_limit,
                                      bool structured_available, bool sensitivities) {
  if (choice == LinearSolverChoice::kGmres) return LinearSolverKind::kGmres;
  if (choice == LinearSolverChoice::kBanded) return LinearSolverKind::kBanded;
  if (choice == LinearSolverChoice::kClassLocal) return LinearSolverKind::kClassLocal;
  const int n = fs.n_states() - fs.n_explicit_states();
  if (choice == LinearSolverChoice::kAuto && n > dense_limit) {
    for (const auto& u : fs.units())
      if (u.spec.has_preconditioner() && static_cast<int>(u.spec.states().size()) > dense_limit)
        return LinearSolverKind::kGmres;
  }
  if (choice == LinearSolverChoice::kAuto && structured_available && !sensitivities && n <= kDenseMax &&
      class_share(fs) >= kBandedShare)
    for (const auto& u : fs.units()) {
      const ClassLayout& layout = u.spec.classes();
      if (!u.spec.is_explicit() && layout.class_local_newton && layout.n >= kClassLocalClasses)
        return LinearSolverKind::kClassLocal;
    }
  if (choice == LinearSolverChoice::kAuto && n > dense_limit) {
    if (structured_available && n <= kDenseMax && class_share(fs) >= kBandedShare) return LinearSolverKind::kBanded;
  }
  return use_dense(fs, choice, dense_limit) ? LinearSolverKind::kDense : LinearSolverKind::kSparse;
}

const char* linear_solver_name(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::kDense:
      return "dense (Eigen LU)";
    case LinearSolverKind::kSparse:
      return "sparse (KLU)";
    case LinearSolverKind::kBanded:
      return "banded (SUNDIALS band LU, outer products and border by Schur complement)";
    case LinearSolverKind::kClassLocal:
      return "class_local (an LU per size class and the border by Schur complement; the couplings between classes "
             "left out of the Newton matrix, not of the equations)";
    default:
      return "gmres (SPGMR, unit preconditioners)";
  }
}

}  // namespace granuflow::detail
