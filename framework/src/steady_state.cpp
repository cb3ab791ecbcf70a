// Steady states F(y, y' = 0) = 0 of a flowsheet.
//
// Structure first: at the starting point the Jacobian tells which quantities the equations cannot fix. An
// accumulator (a state a unit declares as bookkeeping of a flow) is held at its value. A conserved combination b^T y (a
// left null vector c of dF/dy: a batch hold-up, the solids of a closed loop) makes the steady state a family: one of
// its rows is replaced by b^T (y - y0) = 0, so the answer keeps what the start had. If such a combination changes
// at a constant rate whatever the state (c^T F != 0: inflow without outflow, a batch being sprayed), there is no
// steady state at all, and the solve says so instead of failing in Newton.
//
// Then Newton (KINSOL, exact Jacobian, line search) from the start; if it fails, pseudo-transient continuation:
// backward-Euler steps of the dynamics with step sizes that grow as the residual falls (switched evolution
// relaxation), needing nothing from the user, and Newton again from where it led. A root where every state of a
// unit that started non-zero is zero (an emptied population: the trivial root of aggregation and breakage with
// removal) is reported as such.
#include <kinsol/kinsol.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseLU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <memory>
#include <sstream>

#include "consistent_start.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "granuflow/signals.hpp"
#include "granuflow/simulator.hpp"
#include "solver_setup.hpp"

namespace granuflow {

void SteadyOptions::validate() const {
  if (!(t >= 0) || !std::isfinite(t)) throw ConfigError(violation("SteadyOptions.t", t, "s", "t >= 0, finite"));
  if (!(ftol > 0) || !std::isfinite(ftol)) throw ConfigError(violation("SteadyOptions.ftol", ftol, "", "ftol > 0"));
  if (max_iterations < 1)
    throw ConfigError(violation("SteadyOptions.max_iterations", double(max_iterations), "", "max_iterations >= 1"));
  if (max_pseudo_steps < 0)
    throw ConfigError(violation("SteadyOptions.max_pseudo_steps", double(max_pseudo_steps), "", ">= 0"));
}

namespace {

using namespace detail;

// F(y, yp) of the flowsheet with the rows of held states and conserved combinations replaced.
struct SteadySystem {
  DaeSystem* sys = nullptr;
  double t = 0.0;
  bool dense = true;
  int n = 0;
  std::vector<double> y0, zeros;
  std::vector<int> held;                                  // rows replaced by y_r - y0_r
  std::vector<std::pair<int, std::vector<double>>> kept;  // rows replaced by b^T (y - y0) (b dense over states)
  std::string last_error;
  std::vector<double> jac_y0;  // dF/dy at y0 (dense, before the replaced rows), from analyse_structure

  Status residual(const double* y, const double* yp, double* f) {
    const Status s = sys->residual(t, y, yp, f);
    for (int r : held) f[r] = y[r] - y0[r];
    for (const auto& [r, b] : kept) {
      double v = 0;
      for (int i = 0; i < n; ++i) v += b[i] * (y[i] - y0[i]);
      f[r] = v;
    }
    return s;
  }
  // Dense column-major n x n.
  void jacobian_dense(const double* y, const double* yp, double cj, double* J) {
    // Newton's first Jacobian is the one the structure analysis evaluated at the same point
    if (!jac_y0.empty() && cj == 0.0 && std::equal(y0.begin(), y0.end(), y))
      std::copy(jac_y0.begin(), jac_y0.end(), J);
    else
      sys->jacobian(t, y, yp, cj, J, nullptr);
    for (int r : held) {
      for (int c = 0; c < n; ++c) J[size_t(c) * n + r] = 0.0;
      J[size_t(r) * n + r] = 1.0;
    }
    for (const auto& [r, b] : kept)
      for (int c = 0; c < n; ++c) J[size_t(c) * n + r] = b[c];
  }
  // Sparse values in the pattern's order; replaced rows only where the pattern has entries (held: the diagonal,
  // which a unit's own state always has; kept combinations span the pattern of their row's unit).
  void jacobian_sparse(const double* y, const double* yp, double cj, double* vals) {
    sys->jacobian(t, y, yp, cj, nullptr, vals);
    const auto& pat = sys->pattern();
    for (int c = 0; c < pat.n; ++c)
      for (int i = pat.col_ptr[c]; i < pat.col_ptr[c + 1]; ++i) {
        const int r = pat.row_idx[i];
        if (std::find(held.begin(), held.end(), r) != held.end()) vals[i] = (c == r) ? 1.0 : 0.0;
        for (const auto& [kr, b] : kept)
          if (kr == r) vals[i] = b[c];
      }
  }
};

struct KinUser {
  SteadySystem* s;
  unsigned interrupt_calls = 0;  // interrupt_requested(calls)
};

int kin_res(N_Vector u, N_Vector f, void* ud) {
  auto* k = static_cast<KinUser*>(ud);
  if (interrupt_requested(k->interrupt_calls)) return -1;  // the solve then ends with Interrupted
  try {
    return static_cast<int>(k->s->residual(N_VGetArrayPointer(u), k->s->zeros.data(), N_VGetArrayPointer(f)));
  } catch (const std::exception& e) {
    k->s->last_error = e.what();
    return -1;
  }
}

int kin_jac(N_Vector u, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector) {
  auto* k = static_cast<KinUser*>(ud);
  try {  // an exception must not unwind through KINSOL's C frames
    if (k->s->dense) {
      k->s->jacobian_dense(N_VGetArrayPointer(u), k->s->zeros.data(), 0.0, SUNDenseMatrix_Data(J));
    } else {
      set_sparse_pattern(k->s->sys->pattern(), J);
      k->s->jacobian_sparse(N_VGetArrayPointer(u), k->s->zeros.data(), 0.0, SUNSparseMatrix_Data(J));
    }
    return 0;
  } catch (const std::exception& e) {
    k->s->last_error = e.what();
    return -1;
  }
}

void kin_err(int code, const char* module, const char* function, char* msg, void* ud) {
  if (code >= 0) return;
  static_cast<KinUser*>(ud)->s->last_error = std::string(module) + "." + function + ": " + msg;
}

// Algebraic states solved for the given differential states, used to start Newton from a point where recycle flows
// are consistent rather than from structurally singular guesses: by the exact Newton of a run's consistent start
// (dense systems), else or where that gives up by IDACalcIC.
void consistent_initial_values(DaeSystem& sys, bool dense, double t, std::vector<double>& y0) {
  const int n = sys.size();
  if (dense) {
    std::vector<double> y = y0, yp(n, 0.0), ewt(n);
    for (int i = 0; i < n; ++i) ewt[i] = 1.0 / (1e-8 * std::abs(y[i]) + 1e-10);  // IDACalcIC's tolerances below
    JacobianCache cache;
    if (consistent_start(sys, cache, t, ewt.data(), y.data(), yp.data()) > 0) {
      y0 = y;
      return;
    }
  }
  Context C;
  NVec y(n, C.ctx), yp(n, C.ctx), atol(n, C.ctx);
  std::copy(y0.begin(), y0.end(), y.data());
  N_VConst(1e-10, atol.v);
  IdaUser user(&sys, dense);
  Ida ida(C.ctx, user, t, y, yp, 1e-8, atol);
  // Failure here is not fatal: Newton then starts from the unit guesses.
  if (IDACalcIC(ida.mem, IDA_YA_YDP_INIT, t + 1.0) >= 0 && IDAGetConsistentIC(ida.mem, y.v, yp.v) >= 0)
    y0.assign(y.data(), y.data() + n);
}

// "bed (M_0 .. M_9), gas (water)": the states of a combination, by unit.
std::string describe_states(const Flowsheet& fs, const std::vector<int>& states) {
  std::ostringstream os;
  int last_unit = -1;
  std::vector<std::string> names;
  auto flush = [&]() {
    if (last_unit < 0) return;
    os << (os.tellp() > 0 ? ", " : "") << fs.units()[last_unit].name << " (";
    if (names.size() > 3)
      os << names.front() << " .. " << names.back();
    else
      for (size_t i = 0; i < names.size(); ++i) os << (i ? ", " : "") << names[i];
    os << ")";
  };
  for (int s : states) {
    const int u = fs.state_unit(s);
    if (u != last_unit) flush(), names.clear(), last_unit = u;
    names.push_back(fs.units()[u].spec.states()[s - fs.units()[u].offset].name);
  }
  flush();
  return os.str();
}

// Finds the held states and conserved combinations at y0 (dense Jacobians only: the analysis is O(n^3)); throws a
// SolverError when a combination drifts at a constant rate (no steady state).
void analyse_structure(SteadySystem& s, const Flowsheet& fs, std::vector<std::string>& conserved) {
  const int n = s.n;
  std::vector<double>& jac = s.jac_y0;
  std::vector<double> f0(n);
  jac.resize(size_t(n) * n);
  s.sys->jacobian(s.t, s.y0.data(), s.zeros.data(), 0.0, jac.data(), nullptr);
  s.sys->residual(s.t, s.y0.data(), s.zeros.data(), f0.data());
  const auto id = s.sys->differential_id();
  const auto scale = s.sys->scales();
  Eigen::Map<const Eigen::MatrixXd> J(jac.data(), n, n);
  // Conserved combinations: left null vectors of J over the states that are not held (accumulators take up what
  // the others lose), found on J scaled by rows and by the states' scales.
  std::vector<int> keep;
  for (int i = 0; i < n; ++i)
    if (std::find(s.held.begin(), s.held.end(), i) == s.held.end()) keep.push_back(i);
  const int m = static_cast<int>(keep.size());
  Eigen::MatrixXd Js(m, m);
  Eigen::VectorXd row_scale(m);
  for (int a = 0; a < m; ++a) {
    double mx = 0;
    for (int b = 0; b < m; ++b) mx = std::max(mx, std::abs(J(keep[a], keep[b]) * scale[keep[b]]));
    row_scale(a) = mx > 0 ? 1.0 / mx : 1.0;  // an all-zero row is itself a null vector
    for (int b = 0; b < m; ++b) Js(a, b) = row_scale(a) * J(keep[a], keep[b]) * scale[keep[b]];
  }
  // Most flowsheets conserve nothing (continuous processes): a partial-pivoting LU with a condition estimate settles
  // that in a fraction of the rank-revealing factorization's time.
  if (Eigen::PartialPivLU<Eigen::MatrixXd>(Js).rcond() > 1e-7) return;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(Js.transpose());
  lu.setThreshold(1e-9);
  if (lu.rank() == m) return;
  const Eigen::MatrixXd kernel = lu.kernel();
  std::vector<char> used(n, 0);
  for (int r : s.held) used[r] = 1;
  for (int k = 0; k < kernel.cols(); ++k) {
    Eigen::VectorXd cs = row_scale.asDiagonal() * kernel.col(k);  // J^T c = 0 over the kept states
    const double cmax = cs.cwiseAbs().maxCoeff();
    if (!(cmax > 0)) continue;
    cs /= cmax;
    std::vector<int> states;
    std::vector<double> c(n, 0.0);
    double drift = 0, drift_scale = 0;
    for (int a = 0; a < m; ++a)
      if (std::abs(cs(a)) > 1e-12) {
        const int r = keep[a];
        c[r] = cs(a);
        states.push_back(r);
        drift += c[r] * f0[r];
        drift_scale += std::abs(c[r] * f0[r]);
      }
    // c^T F(y, 0) is the same for every y: with y' = 0 it must vanish (its terms cancel to round-off), else the
    // combination drifts forever
    if (std::abs(drift) > 1e-8 * drift_scale) {
      std::ostringstream os;
      os << "flowsheet '" << fs.name() << "' has no steady state at t = " << s.t << " s: the combination of "
         << describe_states(fs, states) << " changes at a constant rate " << -drift
         << " (per s, in the states' units) whatever the state (an inflow without outflow, or a batch that keeps "
            "being fed); simulate it in time instead";
      throw SolverError(os.str(), s.t, fs.units()[fs.state_unit(states.front())].name, std::abs(drift));
    }
    // the differential row of the combination with the largest weight carries b^T (y - y0) = 0 instead
    int row = -1;
    for (int r : states)
      if (id[r] > 0 && !used[r] && (row < 0 || std::abs(c[r]) > std::abs(c[row]))) row = r;
    if (row < 0) continue;
    used[row] = 1;
    std::vector<double> b(n, 0.0);
    for (int r : states)
      if (id[r] > 0) b[r] = c[r];
    s.kept.emplace_back(row, std::move(b));
    conserved.push_back(describe_states(fs, states) + " (kept at its initial value)");
  }
}

double weighted_norm(const std::vector<double>& f, const std::vector<double>& w) {
  double m = 0;
  for (size_t i = 0; i < f.size(); ++i) m = std::max(m, std::abs(f[i] * w[i]));
  return m;
}

// Residual rows carry their equations' units (a flow, an enthalpy, a temperature): each is weighted by the inverse
// of its largest term |dF_r/dy_c| sc_c at the start, so a scaled residual reads as a change of the scaled states and
// one tolerance serves every row (an enthalpy identity of 1e6 J is not held to 1e-10 J).
std::vector<double> row_weights(SteadySystem& s, const std::vector<double>& y, const std::vector<double>& sc) {
  const int n = s.n;
  std::vector<double> big(n, 0.0);
  if (s.dense) {
    std::vector<double> J(size_t(n) * n);
    s.jacobian_dense(y.data(), s.zeros.data(), 0.0, J.data());
    for (int c = 0; c < n; ++c)
      for (int r = 0; r < n; ++r) big[r] = std::max(big[r], std::abs(J[size_t(c) * n + r]) * sc[c]);
  } else {
    const auto& pat = s.sys->pattern();
    std::vector<double> vals(pat.nnz());
    s.jacobian_sparse(y.data(), s.zeros.data(), 0.0, vals.data());
    for (int c = 0; c < n; ++c)
      for (int i = pat.col_ptr[c]; i < pat.col_ptr[c + 1]; ++i)
        big[pat.row_idx[i]] = std::max(big[pat.row_idx[i]], std::abs(vals[i]) * sc[c]);
  }
  std::vector<double> w(n);
  for (int r = 0; r < n; ++r) w[r] = std::isfinite(big[r]) && big[r] > 0.0 ? 1.0 / big[r] : 1.0;
  return w;
}

// Pseudo-transient continuation: backward-Euler steps y_{k+1} - y_k = dtau f(y_{k+1}) on the differential rows (the
// others solved as they are), dtau grown by the fall of the residual (switched evolution relaxation, at least doubled
// while it falls). Returns the number of steps; y holds where it led.
long pseudo_transient(SteadySystem& s, std::vector<double>& y, const SteadyOptions& opt, double ftol_w,
                      const std::vector<double>& w, const std::vector<double>& wf) {
  const int n = s.n;
  const auto id = s.sys->differential_id();
  std::vector<char> free_row(n, 0);
  for (int r = 0; r < n; ++r) free_row[r] = id[r] > 0;
  for (int r : s.held) free_row[r] = 0;
  for (const auto& kr : s.kept) free_row[kr.first] = 0;
  std::vector<double> f(n), yp(n, 0.0), y_old, dy(n), jac, vals;
  auto residual_at = [&](const std::vector<double>& yy, const std::vector<double>& yold, double dtau) {
    for (int i = 0; i < n; ++i) yp[i] = free_row[i] ? (yy[i] - yold[i]) / dtau : 0.0;
    const Status st = s.residual(yy.data(), yp.data(), f.data());
    if (st != Status::kOk) return false;
    for (double v : f)
      if (!std::isfinite(v)) return false;
    return true;
  };
  std::vector<double> steady(n);
  auto steady_norm = [&](const std::vector<double>& yy) {
    if (s.residual(yy.data(), s.zeros.data(), steady.data()) != Status::kOk) return HUGE_VAL;
    return weighted_norm(steady, wf);
  };
  double r_old = steady_norm(y);
  if (!std::isfinite(r_old)) return 0;
  // the first step moves the states by about 1 % of their scale
  double dtau = 1.0;
  {
    double rate = 0;
    for (int i = 0; i < n; ++i)
      if (free_row[i]) rate = std::max(rate, std::abs(steady[i]) * w[i]);
    if (rate > 0) dtau = 1e-2 / rate;
  }
  Eigen::PartialPivLU<Eigen::MatrixXd> dense_lu;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> sparse_lu;
  long steps = 0;
  for (; steps < opt.max_pseudo_steps && r_old > ftol_w && dtau < 1e15; ++steps) {
    y_old = y;
    bool ok = false;
    for (int attempt = 0; attempt < 12 && !ok; ++attempt) {
      y = y_old;
      // Newton on F(y, (y - y_old) / dtau) = 0 with the exact Jacobian dF/dy + dF/dy' / dtau
      for (int it = 0; it < 8; ++it) {
        if (!residual_at(y, y_old, dtau)) break;
        const double fn = weighted_norm(f, wf);
        if (s.dense) {
          jac.resize(size_t(n) * n);
          s.jacobian_dense(y.data(), yp.data(), 1.0 / dtau, jac.data());
          dense_lu.compute(Eigen::Map<Eigen::MatrixXd>(jac.data(), n, n));
          Eigen::Map<Eigen::VectorXd>(dy.data(), n) = dense_lu.solve(Eigen::Map<Eigen::VectorXd>(f.data(), n));
        } else {
          const auto& pat = s.sys->pattern();
          vals.resize(pat.nnz());
          s.jacobian_sparse(y.data(), yp.data(), 1.0 / dtau, vals.data());
          Eigen::Map<const Eigen::SparseMatrix<double>> A(n, n, pat.nnz(), pat.col_ptr.data(), pat.row_idx.data(),
                                                          vals.data());
          sparse_lu.compute(A);
          if (sparse_lu.info() != Eigen::Success) break;
          Eigen::Map<Eigen::VectorXd>(dy.data(), n) = sparse_lu.solve(Eigen::Map<Eigen::VectorXd>(f.data(), n));
        }
        double step = 0;
        for (int i = 0; i < n; ++i) y[i] -= dy[i], step = std::max(step, std::abs(dy[i]) * w[i]);
        if (!std::isfinite(step)) break;
        if (step < 1e-6 || fn < 1e-3 * ftol_w) {
          ok = residual_at(y, y_old, dtau);
          break;
        }
      }
      if (!ok) dtau *= 0.25;
    }
    if (!ok) {
      y = y_old;
      break;
    }
    const double r_new = steady_norm(y);
    // Switched evolution relaxation, but at least doubling while the residual falls: when slow modes dominate the
    // norm (a hold-up relaxing over 1000 s) the residual falls by only dtau / tau per step and plain SER would
    // creep; backward Euler is stable at any step, so only Newton failures (above) hold the step back. Where the
    // residual rises (the dynamics pass a hump: a loop that overfills before it settles) the step still grows,
    // by half: shrinking it with the residual would stall in the hump for thousands of steps.
    const double ratio = r_old / std::max(r_new, 1e-300);
    dtau *= r_new < r_old ? std::min(10.0, std::max(2.0, ratio)) : 1.5;
    r_old = r_new;
  }
  return steps;
}

// KINSOL from y; returns the flag (>= 0 converged) and fills iterations and the residual norm. setup_calls: the
// iterations one Jacobian serves (1: exact Newton; more: modified Newton, which KINSOL refreshes early when a line
// search fails on a stale Jacobian).
int newton(SteadySystem& s, std::vector<double>& y, const SteadyOptions& opt, const std::vector<double>& uscale,
           const std::vector<double>& fscale, long* iterations, double* norm, long setup_calls = 1,
           long max_iterations = 0) {
  const int n = s.n;
  Context C;
  NVec u(n, C.ctx), su(n, C.ctx), sf(n, C.ctx);
  std::copy(y.begin(), y.end(), u.data());
  std::copy(uscale.begin(), uscale.end(), su.data());
  std::copy(fscale.begin(), fscale.end(), sf.data());
  KinUser user{&s};
  void* mem = KINCreate(C.ctx);
  std::unique_ptr<void, void (*)(void*)> guard(mem, [](void* m) { KINFree(&m); });
  check(KINInit(mem, kin_res, u.v), "KINInit");
  check(KINSetUserData(mem, &user), "KINSetUserData");
  check(KINSetErrHandlerFn(mem, kin_err, &user), "KINSetErrHandlerFn");
  check(KINSetFuncNormTol(mem, opt.ftol), "KINSetFuncNormTol");
  check(KINSetNumMaxIters(mem, max_iterations > 0 ? max_iterations : opt.max_iterations), "KINSetNumMaxIters");
  check(KINSetMaxSetupCalls(mem, setup_calls), "KINSetMaxSetupCalls");
  Mat A;
  LinSol LS;
  make_linear_solver(s.dense, *s.sys, u.v, C.ctx, A, LS);
  check(KINSetLinearSolver(mem, LS.s, A.m), "KINSetLinearSolver");
  check(KINSetJacFn(mem, kin_jac), "KINSetJacFn");
  const int flag = KINSol(mem, u.v, KIN_LINESEARCH, su.v, sf.v);
  long it = 0;
  KINGetNumNonlinSolvIters(mem, &it);
  KINGetFuncNorm(mem, norm);
  *iterations += it;
  if (flag >= 0)
    y.assign(u.data(), u.data() + n);
  else
    y.assign(u.data(), u.data() + n);  // the last iterate, for the error message or continuation
  return flag;
}

// Eigenvalues of the dynamics linearized at the steady state: with dF/dy' = I on the differential rows, perturbations
// obey dx' = A dx, A = -(F_dx - F_dz F_zz^-1 F_zx) (algebraic states z eliminated; held accumulators left out, as is
// one zero eigenvalue per conserved combination). Stores the eigenvalue with the largest real part.
void stability(SteadySystem& s, const std::vector<double>& y, size_t conserved, SteadyResult& r) {
  const int n = s.n;
  std::vector<double> jac(size_t(n) * n);
  s.sys->jacobian(s.t, y.data(), s.zeros.data(), 0.0, jac.data(), nullptr);
  Eigen::Map<const Eigen::MatrixXd> J(jac.data(), n, n);
  const auto id = s.sys->differential_id();
  std::vector<int> dx, zx;
  for (int i = 0; i < n; ++i) {
    if (std::find(s.held.begin(), s.held.end(), i) != s.held.end()) continue;
    (id[i] > 0 ? dx : zx).push_back(i);
  }
  const int nd = static_cast<int>(dx.size()), nz = static_cast<int>(zx.size());
  if (nd == 0) return;
  Eigen::MatrixXd A(nd, nd), Fdz(nd, nz), Fzx(nz, nd), Fzz(nz, nz);
  for (int a = 0; a < nd; ++a) {
    for (int b = 0; b < nd; ++b) A(a, b) = -J(dx[a], dx[b]);
    for (int b = 0; b < nz; ++b) Fdz(a, b) = J(dx[a], zx[b]);
  }
  for (int a = 0; a < nz; ++a) {
    for (int b = 0; b < nd; ++b) Fzx(a, b) = J(zx[a], dx[b]);
    for (int b = 0; b < nz; ++b) Fzz(a, b) = J(zx[a], zx[b]);
  }
  if (nz > 0) {
    Eigen::PartialPivLU<Eigen::MatrixXd> lu(Fzz);
    A.noalias() += Fdz * lu.solve(Fzx);
  }
  Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  if (es.info() != Eigen::Success) return;
  std::vector<std::complex<double>> ev(es.eigenvalues().data(), es.eigenvalues().data() + nd);
  // the conserved combinations' zero eigenvalues are the smallest in modulus
  std::sort(ev.begin(), ev.end(), [](auto a, auto b) { return std::abs(a) < std::abs(b); });
  if (conserved >= ev.size()) return;
  ev.erase(ev.begin(), ev.begin() + static_cast<long>(conserved));
  auto top = std::max_element(ev.begin(), ev.end(), [](auto a, auto b) { return a.real() < b.real(); });
  r.stability_known = true;
  r.max_real_eigenvalue = top->real();
  r.imag_of_max = std::abs(top->imag());
}

std::string kin_flag_text(int flag) { return flag_name(KINGetReturnFlagName(flag), "KINSOL error"); }

// Names the unit with the largest residual at the last iterate (if the residual itself throws there, the solver
// failure is still what the caller gets).
[[noreturn]] void throw_no_steady_state(const Flowsheet& fs, SteadySystem& s, const SteadyOptions& opt,
                                        const SteadyResult& r, int flag, const std::vector<double>& y) {
  const int n = s.n;
  std::string msg = "steady-state solve (KINSOL) failed after " + std::to_string(r.iterations) +
                    " iterations: " + kin_flag_text(flag) + (s.last_error.empty() ? "" : " (" + s.last_error + ")");
  if (r.pseudo_steps > 0)
    msg += ", after " + std::to_string(r.pseudo_steps) +
           " pseudo-transient steps (the dynamics did not settle: the flowsheet may have no steady state, e.g. a "
           "hold-up that keeps growing once a discharge reaches its capacity, or one that is unstable; simulate "
           "it in time to see which)";
  std::vector<double> rr(n);
  int iw = 0;
  try {
    s.residual(y.data(), s.zeros.data(), rr.data());
    auto size = [&](int i) { return std::isfinite(rr[i]) ? std::abs(rr[i]) : HUGE_VAL; };
    for (int i = 1; i < n; ++i)
      if (size(i) > size(iw)) iw = i;
  } catch (...) {
    throw SolverError(msg, opt.t, "?", HUGE_VAL);
  }
  throw SolverError(msg + " at " + s.sys->describe_row(iw), opt.t, fs.units()[fs.state_unit(iw)].name,
                    std::abs(rr[iw]));
}

// The trivial root: every differential state of a unit that started non-zero is zero now.
void warn_of_trivial_root(const Flowsheet& fs, const DaeSystem& sys, const std::vector<double>& y0,
                          const std::vector<double>& y, SteadyResult& r) {
  const int n = sys.size();
  const auto sc = sys.scales();
  const auto id = sys.differential_id();
  for (const auto& u : fs.units()) {
    double a0 = 0, a1 = 0;
    const int ns = static_cast<int>(u.spec.states().size());
    for (int k = 0; k < ns; ++k) {
      const int i = u.offset + k;
      if (i >= n || id[i] == 0) continue;
      a0 += std::abs(y0[i]) / sc[i], a1 += std::abs(y[i]) / sc[i];
    }
    if (a0 > 0 && a1 <= 1e-4 * a0)  // Newton approaches a degenerate root only linearly
      r.warnings.push_back("the steady state found is the trivial one: every differential state of unit '" + u.name +
                           "' is zero (e.g. a population that emptied)");
  }
}

// Outputs and the boundary flows at the steady state: quadratures integrate flows, so their rates are the flows
// and their accumulated values have no steady meaning (NaN).
void steady_outputs(const Flowsheet& fs, DaeSystem& sys, double t, const std::vector<double>& y,
                    const std::vector<double>& zeros, const std::vector<double>& yp_full, SteadyResult& r) {
  std::vector<double> qrate(sys.n_quadratures(), 0.0), qnan(sys.n_quadratures(), std::nan(""));
  if (sys.n_quadratures() > 0) sys.quadrature(t, y.data(), zeros.data(), qrate.data());
  r.outputs.assign(fs.n_outputs(), 0.0);
  sys.report(t, r.y.data(), yp_full.data(), qnan.data(), r.outputs.data());
  for (const auto& u : fs.units()) {
    const auto& quads = u.spec.quadratures();
    for (size_t j = 0; j < quads.size(); ++j) {
      const OutputSpec& o = u.spec.outputs()[quads[j].output.i];
      if (o.quantity.empty() || (o.role != OutputRole::kBalanceIn && o.role != OutputRole::kBalanceOut)) continue;
      auto& f = r.boundary_flows[o.quantity];
      (o.role == OutputRole::kBalanceIn ? f.first : f.second) += qrate[u.quad_offset + j];
    }
  }
}

SteadyResult solve_any(Flowsheet& fs, const SteadyOptions& opt, const std::vector<double>* guess) {
  opt.validate();
  const auto wall0 = std::chrono::steady_clock::now();
  if (!fs.finalized()) fs.finalize();
  const bool dense = use_dense(fs, LinearSolverChoice::kAuto, SimOptions().dense_limit);
  const std::shared_ptr<DaeSystem> held = fs.take_system(dense);
  DaeSystem& sys = *held;
  const int n = sys.size();
  if (n == 0) throw ConfigError("flowsheet '" + fs.name() + "' has no states to solve for");
  sys.set_segment_start(opt.t);
  SteadySystem s;
  s.sys = &sys, s.t = opt.t, s.dense = dense, s.n = n;
  s.zeros.assign(n, 0.0);
  std::vector<double> y0;
  sys.initial_values(y0);
  if (guess) {
    if (static_cast<int>(guess->size()) != n && static_cast<int>(guess->size()) != sys.full_size())
      throw ConfigError("steady-state guess has " + std::to_string(guess->size()) + " values, the flowsheet " +
                        std::to_string(sys.full_size()) + " states");
    y0.assign(guess->begin(), guess->begin() + n);  // explicit states (last) follow from the others
  } else {
    consistent_initial_values(sys, dense, opt.t, y0);
  }
  s.y0 = y0;
  SteadyResult r;
  // Accumulators (UnitSpec::add_accumulator: what left a grid) have no steady state of their own.
  for (int i = 0; i < n; ++i)
    if (fs.state_spec(i).accumulator) s.held.push_back(i);
  if (dense) analyse_structure(s, fs, r.conserved);
  const auto sc = sys.scales();
  std::vector<double> uscale(n), w(n);
  for (int i = 0; i < n; ++i) uscale[i] = 1.0 / sc[i], w[i] = 1.0 / sc[i];
  const std::vector<double> wf = row_weights(s, y0, std::vector<double>(sc.begin(), sc.end()));

  // A Jacobian (and its factorization) costs as much as dozens of residuals: modified Newton first, reusing each
  // Jacobian for up to 10 iterations (a sieve-mill loop at 100-200 classes: 3 Jacobians instead of 10, the solve
  // 1.5-3 times faster); exact Newton from the same start where that fails. Modified Newton converges only
  // linearly: past 40 iterations it has spent what exact Newton or the continuation would, so it stops there.
  std::vector<double> y = y0;
  int flag = newton(s, y, opt, uscale, wf, &r.iterations, &r.residual_norm, 10, std::min(40L, opt.max_iterations));
  if (flag < 0) {
    y = y0;
    flag = newton(s, y, opt, uscale, wf, &r.iterations, &r.residual_norm);
  }
  r.method = "newton";
  if (flag < 0 && opt.max_pseudo_steps > 0) {
    y = y0;
    r.pseudo_steps = pseudo_transient(s, y, opt, 1e-6, w, wf);
    flag = newton(s, y, opt, uscale, wf, &r.iterations, &r.residual_norm);
    r.method = "pseudo-transient continuation, then newton";
  }
  if (flag < 0) throw_no_steady_state(fs, s, opt, r, flag, y);
  warn_of_trivial_root(fs, sys, y0, y, r);
  std::vector<double> yp_full(sys.full_size());
  r.y.resize(sys.full_size());
  sys.extend(opt.t, y.data(), s.zeros.data(), r.y.data(), yp_full.data());
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  steady_outputs(fs, sys, opt.t, y, s.zeros, yp_full, r);
  for (auto& w : missed_set_points(fs, opt.t, r.outputs)) r.warnings.push_back(std::move(w));
  if (opt.stability && dense) {
    const auto t0 = std::chrono::steady_clock::now();
    stability(s, y, s.kept.size(), r);
    r.stability_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  sys.end_run();
  return r;
}

}  // namespace

SteadyResult solve_steady_state(Flowsheet& fs, const SteadyOptions& opt, const std::vector<double>* guess) {
  return interruptible([&] { return solve_any(fs, opt, guess); });
}

}  // namespace granuflow
