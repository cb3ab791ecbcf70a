#include "granuflow/simulator.hpp"

#include <idas/idas.h>
#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "consistent_sensitivities.hpp"
#include "eigen_linear_solver.hpp"
#include "granuflow/errors.hpp"

namespace granuflow {

void SimOptions::validate(bool scene_keys) const {
  // Named as the scene file's keys (t_end, output.times[i], solver.rtol ...) or as the fields of SimOptions.
  auto name = [scene_keys](const std::string& field, const std::string& key) {
    return scene_keys ? key : "SimOptions." + field;
  };
  auto fail = [&](const std::string& field, const std::string& key, double v, const std::string& unit,
                  const std::string& rule) { throw ConfigError(violation(name(field, key), v, unit, rule)); };
  if (!(t_end > 0) || !std::isfinite(t_end)) fail("t_end", "t_end", t_end, scene_keys ? "s" : "", "t_end > 0");
  if (!(rtol > 0 && rtol < 1)) fail("rtol", "solver.rtol", rtol, "", "0 < rtol < 1");
  if (!(atol > 0)) fail("atol", "solver.atol", atol, "", "atol > 0");
  if (max_steps < 1) fail("max_steps", "solver.max_steps", double(max_steps), "", "max_steps >= 1");
  if (!(max_step >= 0)) fail("max_step", "solver.max_step", max_step, scene_keys ? "s" : "", "max_step >= 0");
  if (t_out.empty() && n_out < 2) fail("n_out", "output.n", n_out, "", "n_out >= 2");
  for (size_t i = 0; i < t_out.size(); ++i) {
    const std::string field = "t_out[" + std::to_string(i) + "]", key = "output.times[" + std::to_string(i) + "]";
    if (!(t_out[i] >= 0 && t_out[i] <= t_end * (1 + 1e-12)))
      fail(field, key, t_out[i], scene_keys ? "s" : "", "0 <= t_out <= t_end (" + fmt_num(t_end) + " s)");
    if (i > 0 && !(t_out[i] > t_out[i - 1]))
      fail(field, key, t_out[i], scene_keys ? "s" : "", "t_out increasing (previous " + fmt_num(t_out[i - 1]) + " s)");
  }
  if (linear_solver != "auto" && linear_solver != "dense" && linear_solver != "sparse")
    throw ConfigError(name("linear_solver", "solver.linear_solver") + " = '" + linear_solver +
                      "': not one of auto, dense, sparse");
}

void SteadyOptions::validate() const {
  if (!(ftol > 0)) throw ConfigError(violation("SteadyOptions.ftol", ftol, "", "ftol > 0"));
  if (max_iterations < 1)
    throw ConfigError(violation("SteadyOptions.max_iterations", double(max_iterations), "", "max_iterations >= 1"));
}

namespace {

// RAII holders for the SUNDIALS objects.
struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};
struct NVec {
  N_Vector v = nullptr;
  NVec(int n, SUNContext ctx) : v(N_VNew_Serial(n, ctx)) { N_VConst(0.0, v); }
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

// Dense: Eigen's blocked LU behind a SUNDenseMatrix; sparse: KLU on the flowsheet's sparsity pattern.
void make_linear_solver(bool dense, const DaeSystem& sys, N_Vector y, SUNContext ctx, Mat& a, LinSol& ls) {
  const int n = sys.size();
  if (dense) {
    a.m = SUNDenseMatrix(n, n, ctx);
    // DaeSystem::jacobian writes all n^2 entries, so IDA's zeroing before each evaluation is skipped.
    a.m->ops->zero = [](SUNMatrix) -> int { return 0; };
    ls.s = detail::make_eigen_dense_solver(ctx);
  } else {
    a.m = SUNSparseMatrix(n, n, sys.pattern().nnz(), CSC_MAT, ctx);
    ls.s = SUNLinSol_KLU(y, a.m, ctx);
  }
}

std::string ida_flag_text(int flag) {
  const char* name = IDAGetReturnFlagName(flag);
  std::string s = name ? name : "IDA error";
  free(const_cast<char*>(name));
  return s;
}

void check(int flag, const char* call) {
  if (flag < 0) throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

// A dense Jacobian kept for reuse, the way CVODE keeps df/dy: IDA sets its Newton matrix up again whenever
// cj = alpha / h moves by 25 %, and with every differential state's residual of the form y'_k - f(y) (all
// units' contract, checked on the first evaluation of a run) only the diagonal of the differential states
// depends on cj. An evaluation at most kMaxAge steps old is reused with cj updated, unless Newton (of the states
// or of their sensitivities) has failed to converge since; IDACalcIC and each segment start from a fresh one.
struct JacobianCache {
  static constexpr long kMaxAge = 20;
  std::vector<double> jac;        // column-major n x n, evaluated at cj
  std::vector<int> differential;  // indices of the differential states
  double cj = 0.0;
  long step = 0, conv_fails = 0;
  bool valid = false;
  int reusable = -1;  // -1 unknown (checked on the first evaluation), 0 no, 1 yes
};

// State shared by the IDAS callbacks.
struct IdaUser {
  IdaUser(DaeSystem* s, bool d, std::vector<int> params = {}) : sys(s), dense(d), sens_params(std::move(params)) {}
  DaeSystem* sys;
  bool dense;
  std::vector<int> sens_params;
  std::string last_error;
  std::vector<const double*> yS, ypS;
  std::vector<double*> rS, qS;
  void* mem = nullptr;  // the IDA integrator, when Jacobians may be reused (simulate, dense)
  JacobianCache cache;
  bool fresh_only = false;  // consistent initialization: Newton from a guess needs the Jacobian of each iterate
};

int ida_res(realtype t, N_Vector y, N_Vector yp, N_Vector r, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    return static_cast<int>(u->sys->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(r)));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_jac(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
            N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
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
          step - k.step < JacobianCache::kMaxAge) {
        std::copy(k.jac.begin(), k.jac.end(), a);
        for (int i : k.differential) a[size_t(i) * n + i] += cj - k.cj;
        return 0;
      }
      u->sys->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, a, nullptr);
      if (!u->mem) return 0;
      if (k.reusable < 0) {  // dF/dy' must be the identity on the differential states, zero elsewhere
        std::vector<double> shifted(size_t(n) * n);
        u->sys->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj + 1.0, shifted.data(), nullptr);
        const auto id = u->sys->differential_id();
        k.reusable = 1;
        for (int c = 0; c < n && k.reusable; ++c)
          for (int r = 0; r < n; ++r) {
            const double d = shifted[size_t(c) * n + r] - a[size_t(c) * n + r];
            const double expect = (r == c && id[r] == 1.0) ? 1.0 : 0.0;
            if (std::abs(d - expect) > 1e-9 * (1.0 + std::abs(a[size_t(c) * n + r]))) {
              k.reusable = 0;
              break;
            }
          }
        for (int i = 0; i < n; ++i)
          if (id[i] == 1.0) k.differential.push_back(i);
      }
      if (k.reusable == 1) {
        k.jac.assign(a, a + size_t(n) * n);
        k.cj = cj;
        k.step = step;
        k.conv_fails = fails;
        k.valid = true;
      }
    } else {
      const auto& pat = u->sys->pattern();
      sunindextype* cp = SUNSparseMatrix_IndexPointers(J);
      sunindextype* ri = SUNSparseMatrix_IndexValues(J);
      for (int c = 0; c <= pat.n; ++c) cp[c] = pat.col_ptr[c];
      for (int k = 0; k < pat.nnz(); ++k) ri[k] = pat.row_idx[k];
      u->sys->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, nullptr, SUNSparseMatrix_Data(J));
    }
    return 0;
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_sens_res(int ns, realtype t, N_Vector y, N_Vector yp, N_Vector, N_Vector* yS, N_Vector* ypS, N_Vector* rS,
                 void* ud, N_Vector, N_Vector, N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
  u->yS.resize(ns);
  u->ypS.resize(ns);
  u->rS.resize(ns);
  for (int k = 0; k < ns; ++k) {
    u->yS[k] = N_VGetArrayPointer(yS[k]);
    u->ypS[k] = N_VGetArrayPointer(ypS[k]);
    u->rS[k] = N_VGetArrayPointer(rS[k]);
  }
  try {
    return static_cast<int>(u->sys->sens_residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), u->sens_params,
                                                  u->yS.data(), u->ypS.data(), u->rS.data()));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_quad(realtype t, N_Vector y, N_Vector yp, N_Vector q, void* ud) {
  auto* u = static_cast<IdaUser*>(ud);
  try {
    return static_cast<int>(
        u->sys->quadrature(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(q)));
  } catch (const std::exception& e) {
    u->last_error = e.what();
    return -1;
  }
}

int ida_quad_sens(int ns, realtype t, N_Vector y, N_Vector yp, N_Vector* yS, N_Vector*, N_Vector, N_Vector* qS,
                  void* ud, N_Vector, N_Vector, N_Vector) {
  auto* u = static_cast<IdaUser*>(ud);
  u->yS.resize(ns);
  u->qS.resize(ns);
  for (int k = 0; k < ns; ++k) {
    u->yS[k] = N_VGetArrayPointer(yS[k]);
    u->qS[k] = N_VGetArrayPointer(qS[k]);
  }
  try {
    return static_cast<int>(u->sys->quadrature_sens(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), u->sens_params,
                                                    u->yS.data(), u->qS.data()));
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

// One IDA integrator over a DaeSystem, set up the same way for simulation and for the consistent starting point
// of a steady-state solve: residual, tolerances, differential/algebraic ids, the linear solver and exact Jacobian.
struct Ida {
  void* mem = nullptr;
  Mat A;
  LinSol LS;
  Ida(SUNContext ctx, IdaUser& user, double t0, const NVec& y, const NVec& yp, double rtol, const NVec& atol) {
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
    make_linear_solver(user.dense, sys, y.v, ctx, A, LS);
    check(IDASetLinearSolver(mem, LS.s, A.m), "IDASetLinearSolver");
    check(IDASetJacFn(mem, ida_jac), "IDASetJacFn");
  }
  ~Ida() { IDAFree(&mem); }
  Ida(const Ida&) = delete;
  Ida& operator=(const Ida&) = delete;
};

// Dense Jacobians (explicit units inlined) up to `dense_limit` unknowns, and beyond that while the Jacobian is
// mostly full anyway (aggregation couples every size class with every other): at 200 classes the headline
// scene took 4.9 s with KLU on its 1034 states (60 % full) and 0.24 s dense on 429 unknowns with the spray
// zone inlined. Past kDenseMax unknowns the dense matrix itself is the problem.
constexpr int kDenseMax = 3000;
constexpr double kDenseFill = 0.25;
bool use_dense(Flowsheet& fs, const std::string& choice, int dense_limit) {
  if (choice != "auto") return choice == "dense";
  const int n = fs.n_states() - fs.n_explicit_states();
  if (n <= dense_limit) return true;
  if (n > kDenseMax) return false;
  return DaeSystem(fs, false).fill() >= kDenseFill;
}

}  // namespace

SimResult simulate(Flowsheet& fs, const SimOptions& opt) {
  opt.validate();
  const auto wall0 = std::chrono::steady_clock::now();
  if (!fs.finalized()) fs.finalize();
  // Explicit units are inlined whenever the system is solved densely.
  const bool dense = use_dense(fs, opt.linear_solver, opt.dense_limit);
  DaeSystem sys(fs, dense);
  const int n = sys.size(), n_full = sys.full_size(), nq = sys.n_quadratures();
  if (n == 0) throw ConfigError("flowsheet '" + fs.name() + "' has no states to integrate");

  std::vector<int> sens_ids;
  for (const auto& name : opt.sensitivities) {
    const int id = fs.param_id(name);
    if (fs.has_input(id))
      throw ConfigError("sensitivity parameter '" + name +
                        "' is a time-dependent input; only constants can be differentiated");
    sens_ids.push_back(id);
  }
  std::vector<double> t_out = opt.t_out;
  if (t_out.empty())
    for (int i = 0; i < opt.n_out; ++i) t_out.push_back(opt.t_end * i / (opt.n_out - 1));

  Context C;
  NVec y(n, C.ctx), yp(n, C.ctx), atol(n, C.ctx);
  std::vector<double> y0;
  sys.initial_values(y0);
  std::copy(y0.begin(), y0.end(), y.data());
  const auto scales = sys.scales();
  for (int i = 0; i < n; ++i) atol.data()[i] = opt.atol * scales[i];

  IdaUser user(&sys, dense, sens_ids);
  Ida ida(C.ctx, user, 0.0, y, yp, opt.rtol, atol);
  void* mem = ida.mem;
  if (dense) user.mem = mem;
  // Algebraic states (and their sensitivities) follow the differential ones exactly; testing their local
  // error only makes the integrator stall at kinks of closures (floors, caps, the drying curve's knee).
  check(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg");
  check(IDASetMaxNumSteps(mem, opt.max_steps), "IDASetMaxNumSteps");
  if (opt.max_step > 0) check(IDASetMaxStep(mem, opt.max_step), "IDASetMaxStep");

  // Quadratures (integrals of flows): outside the Newton system, inside the error test.
  NVec q(std::max(nq, 1), C.ctx), qatol(std::max(nq, 1), C.ctx);
  if (nq > 0) {
    const auto qs = sys.quadrature_scales();
    for (int i = 0; i < nq; ++i) qatol.data()[i] = opt.atol * qs[i];
    check(IDAQuadInit(mem, ida_quad, q.v), "IDAQuadInit");
    check(IDAQuadSVtolerances(mem, opt.rtol, qatol.v), "IDAQuadSVtolerances");
    check(IDASetQuadErrCon(mem, SUNTRUE), "IDASetQuadErrCon");
  }

  const int ns = static_cast<int>(sens_ids.size());
  N_Vector* yS = nullptr;
  N_Vector* ypS = nullptr;
  N_Vector* qS = nullptr;
  if (ns > 0) {
    yS = N_VCloneVectorArray(ns, y.v);
    ypS = N_VCloneVectorArray(ns, y.v);
    std::vector<std::vector<double>> yS0;
    sys.initial_sensitivities(sens_ids, yS0);
    for (int k = 0; k < ns; ++k) {
      std::copy(yS0[k].begin(), yS0[k].end(), N_VGetArrayPointer(yS[k]));
      N_VConst(0.0, ypS[k]);
    }
    check(IDASensInit(mem, ns, IDA_STAGGERED, ida_sens_res, yS, ypS), "IDASensInit");
    check(IDASensEEtolerances(mem), "IDASensEEtolerances");
    check(IDASetSensErrCon(mem, opt.sens_error_control ? SUNTRUE : SUNFALSE), "IDASetSensErrCon");
    if (nq > 0) {
      qS = N_VCloneVectorArray(ns, q.v);
      for (int k = 0; k < ns; ++k) N_VConst(0.0, qS[k]);
      check(IDAQuadSensInit(mem, ida_quad_sens, qS), "IDAQuadSensInit");
      check(IDAQuadSensEEtolerances(mem), "IDAQuadSensEEtolerances");
      check(IDASetQuadSensErrCon(mem, opt.sens_error_control ? SUNTRUE : SUNFALSE), "IDASetQuadSensErrCon");
    }
  }
  // Consistent initial sensitivities come from one linear solve (consistent_sensitivities.hpp), not from
  // IDACalcIC's sensitivity Newton: sensitivities are off during IDACalcIC and re-initialized after it.
  auto sens_initial_conditions = [&](double t) {
    std::vector<double*> s(ns), sp(ns);
    for (int k = 0; k < ns; ++k) s[k] = N_VGetArrayPointer(yS[k]), sp[k] = N_VGetArrayPointer(ypS[k]);
    detail::consistent_sensitivities(sys, user.dense, t, y.data(), yp.data(), sens_ids, s.data(), sp.data());
    check(IDAReInit(mem, t, y.v, yp.v), "IDAReInit");
    if (nq > 0) check(IDAQuadReInit(mem, q.v), "IDAQuadReInit");
    check(IDASensReInit(mem, IDA_STAGGERED, yS, ypS), "IDASensReInit");
    check(IDASensEEtolerances(mem), "IDASensEEtolerances");
    // IDACalcIC's setup ran with sensitivities off and cleared their error-control flag: set it again.
    check(IDASetSensErrCon(mem, opt.sens_error_control ? SUNTRUE : SUNFALSE), "IDASetSensErrCon");
    if (nq > 0) {
      check(IDAQuadSensReInit(mem, qS), "IDAQuadSensReInit");
      check(IDAQuadSensEEtolerances(mem), "IDAQuadSensEEtolerances");
      check(IDASetQuadSensErrCon(mem, opt.sens_error_control ? SUNTRUE : SUNFALSE), "IDASetQuadSensErrCon");
    }
  };
  struct SensGuard {
    N_Vector* a;
    N_Vector* b;
    N_Vector* c;
    int n;
    ~SensGuard() {
      if (a) N_VDestroyVectorArray(a, n);
      if (b) N_VDestroyVectorArray(b, n);
      if (c) N_VDestroyVectorArray(c, n);
    }
  } sens_guard{yS, ypS, qS, ns};

  SimResult res;
  res.state_names = fs.state_names();
  res.output_names = fs.output_names();
  res.sens_params = opt.sensitivities;
  const int no = static_cast<int>(res.output_names.size());
  res.stats.states = n;
  res.stats.explicit_states = n_full - n;
  res.stats.quadratures = nq;
  res.stats.linear_solver = user.dense ? "dense (Eigen LU)" : "sparse (KLU)";

  auto fail = [&](int flag, const char* what) {
    realtype tcur = 0;
    IDAGetCurrentTime(mem, &tcur);
    // Locate the worst weighted residual at the last accepted state.
    NVec r(n, C.ctx), w(n, C.ctx);
    IDAGetErrWeights(mem, w.v);
    std::string where = "unknown unit", uname = "?";
    double worst = 0;
    try {
      sys.residual(tcur, y.data(), yp.data(), r.data());
      int iw = 0;
      for (int i = 0; i < n; ++i) {
        const double v = std::isfinite(r.data()[i]) ? std::abs(r.data()[i] * w.data()[i]) : HUGE_VAL;
        if (v > worst) worst = v, iw = i;
      }
      where = sys.describe_row(iw);
      uname = fs.units()[fs.state_unit(iw)].name;
    } catch (...) {
    }
    std::ostringstream os;
    os << what << " failed at t = " << tcur << " s in " << where << ": " << ida_flag_text(flag)
       << (user.last_error.empty() ? "" : " (" + user.last_error + ")") << "; worst weighted residual " << worst;
    throw SolverError(os.str(), tcur, uname, worst);
  };

  auto add_stats = [&]() {
    long v = 0;
    IDAGetNumSteps(mem, &v), res.stats.steps += v;
    IDAGetNumLinSolvSetups(mem, &v), res.stats.linear_setups += v;
    IDAGetNumNonlinSolvIters(mem, &v), res.stats.nonlinear_iterations += v;
    IDAGetNumErrTestFails(mem, &v), res.stats.error_test_failures += v;
    IDAGetNumNonlinSolvConvFails(mem, &v), res.stats.nonlinear_failures += v;
  };

  std::vector<double> y_full(n_full), yp_full(n_full), out(no);
  std::vector<std::vector<double>> s_full(ns, std::vector<double>(n_full)), qs_now(ns, std::vector<double>(nq)),
      dout(ns, std::vector<double>(no));
  auto record = [&](double t) {
    realtype tret = t;
    if (nq > 0 && t > 0) IDAGetQuad(mem, &tret, q.v);
    sys.extend(t, y.data(), yp.data(), y_full.data(), yp_full.data());
    res.t.push_back(t);
    res.y.insert(res.y.end(), y_full.begin(), y_full.end());
    res.yp.insert(res.yp.end(), yp_full.begin(), yp_full.end());
    if (no > 0) sys.report(t, y_full.data(), yp_full.data(), q.data(), out.data());
    for (double& v : out)
      if (!std::isfinite(v)) v = std::nan("");
    res.outputs.insert(res.outputs.end(), out.begin(), out.end());
    if (ns > 0) {
      if (t > 0) IDAGetSens(mem, &tret, yS);
      if (t > 0 && nq > 0) IDAGetQuadSens(mem, &tret, qS);
      std::vector<const double*> src(ns), qsrc(ns);
      std::vector<double*> dst(ns), dsto(ns);
      for (int k = 0; k < ns; ++k) {
        src[k] = N_VGetArrayPointer(yS[k]), dst[k] = s_full[k].data(), dsto[k] = dout[k].data();
        for (int i = 0; i < nq; ++i) qs_now[k][i] = t > 0 ? N_VGetArrayPointer(qS[k])[i] : 0.0;
        qsrc[k] = qs_now[k].data();
      }
      sys.extend_sensitivities(t, y.data(), yp.data(), sens_ids, src.data(), dst.data());
      for (int k = 0; k < ns; ++k) res.sens.insert(res.sens.end(), s_full[k].begin(), s_full[k].end());
      if (no > 0) {
        std::vector<const double*> sf(ns);
        for (int k = 0; k < ns; ++k) sf[k] = s_full[k].data();
        sys.report_sensitivities(t, y_full.data(), yp_full.data(), q.data(), sens_ids, sf.data(), qsrc.data(),
                                 dsto.data());
        for (int k = 0; k < ns; ++k) res.output_sens.insert(res.output_sens.end(), dout[k].begin(), dout[k].end());
      }
    }
  };

  // Segments between breakpoints; each starts with consistent initialization.
  std::vector<double> ends = fs.breakpoints(opt.t_end);
  ends.push_back(opt.t_end);
  double t0 = 0.0;
  size_t iout = 0;
  for (size_t seg = 0; seg < ends.size(); ++seg) {
    const double t1 = ends[seg];
    sys.set_segment_start(t0);
    if (seg > 0) {
      add_stats();
      check(IDAReInit(mem, t0, y.v, yp.v), "IDAReInit");
      if (nq > 0) {
        realtype tq = t0;
        IDAGetQuad(mem, &tq, q.v);
        check(IDAQuadReInit(mem, q.v), "IDAQuadReInit");
      }
      ++res.stats.reinits;
    }
    if (ns > 0) check(IDASensToggleOff(mem), "IDASensToggleOff");
    user.cache.valid = false;  // a segment starts from a fresh Jacobian
    // IDACalcIC's Newton matrix is dF/dy + dF/dy' / h_ic with h_ic = 1e-3 (tout1 - t0); the exact one for its
    // unknowns (y' differential, y algebraic) lacks dF/dy of the differential states, so a long h_ic slows
    // Newton (headline scene, tout1 at the segment end: 55 residuals), while a very short one loosens the test
    // on y', whose correction is measured times h_ic. 1 % of the segment (15 residuals there); not the first
    // output time, so that results do not depend on which output times are asked for.
    const double tout1 = t0 + 0.01 * (t1 - t0);
    user.fresh_only = true;
    int flag = IDACalcIC(mem, IDA_YA_YDP_INIT, tout1);
    user.fresh_only = false;
    if (flag < 0) fail(flag, "consistent initialization (IDACalcIC)");
    check(IDAGetConsistentIC(mem, y.v, yp.v), "IDAGetConsistentIC");
    user.cache.valid = false;  // evaluated at IDACalcIC's iterates
    if (ns > 0) sens_initial_conditions(t0);
    while (iout < t_out.size() && t_out[iout] <= t0 + 1e-12 * std::max(1.0, t0)) {
      if (seg == 0) record(t_out[iout]);
      ++iout;
    }
    check(IDASetStopTime(mem, t1), "IDASetStopTime");
    double t = t0;
    while (t < t1) {
      const bool to_output = iout < t_out.size() && t_out[iout] <= t1;
      const double target = to_output ? t_out[iout] : t1;
      realtype tret = t;
      flag = IDASolve(mem, target, &tret, y.v, yp.v, IDA_NORMAL);
      if (flag < 0) fail(flag, "IDASolve");
      t = tret;
      if (to_output && tret >= t_out[iout] * (1 - 1e-14)) {
        record(t_out[iout]);
        ++iout;
      }
      if (flag == IDA_TSTOP_RETURN) break;
    }
    if (ns > 0) {
      realtype tret;
      IDAGetSens(mem, &tret, yS);
      IDAGetSensDky(mem, t1, 1, ypS);
      if (nq > 0) IDAGetQuadSens(mem, &tret, qS);
    }
    if (nq > 0) {
      realtype tret;
      IDAGetQuad(mem, &tret, q.v);
    }
    t0 = t1;
  }
  add_stats();
  res.stats.residuals = sys.residual_count();
  res.stats.jacobians = sys.jacobian_count();
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

// ---------------------------------------------------------------- steady state (KINSOL)
namespace {
struct KinUser {
  DaeSystem* sys;
  double t;
  bool dense;
  std::vector<double> zeros;
  std::string last_error;
  std::vector<int> pinned;
  std::vector<double> pinned_value;
};

int kin_res(N_Vector u, N_Vector f, void* ud) {
  auto* k = static_cast<KinUser*>(ud);
  try {
    const int s =
        static_cast<int>(k->sys->residual(k->t, N_VGetArrayPointer(u), k->zeros.data(), N_VGetArrayPointer(f)));
    for (size_t i = 0; i < k->pinned.size(); ++i)
      N_VGetArrayPointer(f)[k->pinned[i]] = N_VGetArrayPointer(u)[k->pinned[i]] - k->pinned_value[i];
    return s;
  } catch (const std::exception& e) {
    k->last_error = e.what();
    return -1;
  }
}

int kin_jac(N_Vector u, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector) {
  auto* k = static_cast<KinUser*>(ud);
  try {  // an exception must not unwind through KINSOL's C frames
    if (k->dense) {
      k->sys->jacobian(k->t, N_VGetArrayPointer(u), k->zeros.data(), 0.0, SUNDenseMatrix_Data(J), nullptr);
      const auto n = SUNDenseMatrix_Rows(J);
      for (int p : k->pinned) {
        for (sunindextype c = 0; c < n; ++c) SUNDenseMatrix_Data(J)[c * n + p] = 0.0;
        SUNDenseMatrix_Data(J)[sunindextype(p) * n + p] = 1.0;
      }
    } else {
      const auto& pat = k->sys->pattern();
      for (int c = 0; c <= pat.n; ++c) SUNSparseMatrix_IndexPointers(J)[c] = pat.col_ptr[c];
      for (int i = 0; i < pat.nnz(); ++i) SUNSparseMatrix_IndexValues(J)[i] = pat.row_idx[i];
      k->sys->jacobian(k->t, N_VGetArrayPointer(u), k->zeros.data(), 0.0, nullptr, SUNSparseMatrix_Data(J));
      // The diagonal is in the pattern (a unit depends on its own states), so pinning stays inside it.
      for (int p : k->pinned)
        for (int c = 0; c < pat.n; ++c)
          for (int i = pat.col_ptr[c]; i < pat.col_ptr[c + 1]; ++i)
            if (pat.row_idx[i] == p) SUNSparseMatrix_Data(J)[i] = (c == p) ? 1.0 : 0.0;
    }
    return 0;
  } catch (const std::exception& e) {
    k->last_error = e.what();
    return -1;
  }
}

void kin_err(int code, const char* module, const char* function, char* msg, void* ud) {
  if (code >= 0) return;
  static_cast<KinUser*>(ud)->last_error = std::string(module) + "." + function + ": " + msg;
}

// Algebraic states solved for the given differential states (IDACalcIC), used to start Newton from a point
// where recycle flows are consistent rather than from structurally singular guesses.
void consistent_initial_values(DaeSystem& sys, bool dense, double t, std::vector<double>& y0) {
  const int n = sys.size();
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
}  // namespace

SteadyResult solve_steady_state(Flowsheet& fs, const SteadyOptions& opt, const std::vector<double>* guess) {
  opt.validate();
  if (!fs.finalized()) fs.finalize();
  const bool dense = use_dense(fs, "auto", SimOptions().dense_limit);
  DaeSystem sys(fs, dense);
  const int n = sys.size();
  sys.set_segment_start(opt.t);
  Context C;
  NVec u(n, C.ctx), su(n, C.ctx), sf(n, C.ctx);
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
  std::copy(y0.begin(), y0.end(), u.data());
  const auto sc = sys.scales();
  for (int i = 0; i < n; ++i) su.data()[i] = 1.0 / sc[i];
  N_VConst(1.0, sf.v);
  KinUser user{&sys, opt.t, dense, std::vector<double>(n, 0.0), {}, {}, {}};
  // Pure accumulators (a differential state no equation depends on, e.g. the mass collected by a product sink)
  // have no steady state: hold them at their initial value and drop their own equation.
  {
    // Column c of dF/dy is zero: on the sparse path, only its pattern entries can be nonzero (no dense n^2 copy).
    std::vector<char> nonzero(n, 0);
    if (dense) {
      std::vector<double> jac(size_t(n) * n);
      sys.jacobian(opt.t, y0.data(), user.zeros.data(), 0.0, jac.data(), nullptr);
      for (int c = 0; c < n; ++c)
        for (int r = 0; r < n && !nonzero[c]; ++r) nonzero[c] = jac[size_t(c) * n + r] != 0.0;
    } else {
      const SparsityPattern& pat = sys.pattern();
      std::vector<double> vals(pat.nnz());
      sys.jacobian(opt.t, y0.data(), user.zeros.data(), 0.0, nullptr, vals.data());
      for (int c = 0; c < n; ++c)
        for (int q = pat.col_ptr[c]; q < pat.col_ptr[c + 1] && !nonzero[c]; ++q) nonzero[c] = vals[q] != 0.0;
    }
    const auto id = sys.differential_id();
    for (int c = 0; c < n; ++c)
      if (id[c] > 0 && !nonzero[c]) user.pinned.push_back(c), user.pinned_value.push_back(y0[c]);
  }
  void* mem = KINCreate(C.ctx);
  std::unique_ptr<void, void (*)(void*)> guard(mem, [](void* m) { KINFree(&m); });
  check(KINInit(mem, kin_res, u.v), "KINInit");
  check(KINSetUserData(mem, &user), "KINSetUserData");
  check(KINSetErrHandlerFn(mem, kin_err, &user), "KINSetErrHandlerFn");
  check(KINSetFuncNormTol(mem, opt.ftol), "KINSetFuncNormTol");
  check(KINSetNumMaxIters(mem, opt.max_iterations), "KINSetNumMaxIters");
  check(KINSetMaxSetupCalls(mem, 1), "KINSetMaxSetupCalls");  // exact Newton: the Jacobian is cheap and exact
  Mat A;
  LinSol LS;
  make_linear_solver(user.dense, sys, u.v, C.ctx, A, LS);
  check(KINSetLinearSolver(mem, LS.s, A.m), "KINSetLinearSolver");
  check(KINSetJacFn(mem, kin_jac), "KINSetJacFn");
  const int flag = KINSol(mem, u.v, KIN_LINESEARCH, su.v, sf.v);
  SteadyResult r;
  long it = 0;
  KINGetNumNonlinSolvIters(mem, &it);
  KINGetFuncNorm(mem, &r.residual_norm);
  r.iterations = it;
  if (flag < 0) {
    char* name = KINGetReturnFlagName(flag);
    std::string msg = std::string("steady-state solve (KINSOL) failed after ") + std::to_string(it) +
                      " iterations: " + (name ? name : "") +
                      (user.last_error.empty() ? "" : " (" + user.last_error + ")");
    free(name);
    // Name the unit with the largest residual at the last iterate (if the residual itself throws there, the
    // solver failure is still what the caller gets).
    std::vector<double> rr(n);
    int iw = 0;
    try {
      sys.residual(opt.t, u.data(), user.zeros.data(), rr.data());
      auto size = [&](int i) { return std::isfinite(rr[i]) ? std::abs(rr[i]) : HUGE_VAL; };
      for (int i = 1; i < n; ++i)
        if (size(i) > size(iw)) iw = i;
    } catch (...) {
      throw SolverError(msg, opt.t, "?", HUGE_VAL);
    }
    throw SolverError(msg + " at " + sys.describe_row(iw), opt.t, fs.units()[fs.state_unit(iw)].name, std::abs(rr[iw]));
  }
  std::vector<double> yp_full(sys.full_size());
  r.y.resize(sys.full_size());
  sys.extend(opt.t, u.data(), user.zeros.data(), r.y.data(), yp_full.data());
  return r;
}

}  // namespace granuflow
