#include "banded_lowrank_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "direct_linear_solver.hpp"
#include "granuflow/dae_system.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow::detail {

ClassStructure class_structure(const DaeSystem& sys) {
  const int n = sys.size();
  ClassStructure s;
  s.cls.assign(n, -1), s.group.assign(n, -1);
  for (const auto& u : sys.flowsheet().units()) {
    const ClassLayout& layout = u.spec.classes();
    if (u.spec.is_explicit() || layout.n <= 0 || layout.state_blocks.empty()) continue;
    for (StateId b : layout.state_blocks)
      for (int i = 0; i < layout.n; ++i) {
        const int k = u.offset + b.i + i;
        if (k < n) s.cls[k] = i, s.group[k] = s.groups;
      }
    ++s.groups;
  }
  return s;
}

namespace {

// A matrix whose relative residual off the band exceeds this is not of the form band + outer products: the entries
// there are products of the same two vectors up to round-off of a few operations.
constexpr double kOutsideTol = 1e-11;
constexpr int kMissesBeforeSkip = 2, kUntestedSetups = 8;

struct Content {
  ClassStructure st;
  int n = 0, nc = 0;
  std::vector<int> core, pos, border;     // core position -> state; state -> position (-1: border)
  std::vector<std::vector<int>> members;  // per group its states
  std::vector<double> u, v;               // per state, its group's outer product (0 without one)
  std::vector<int> terms;                 // groups with an outer product
  SUNContext ctx = nullptr;
  SUNMatrix band = nullptr;
  SUNLinearSolver band_ls = nullptr;
  N_Vector work = nullptr;
  int ml = -1, mu = -1;
  Eigen::MatrixXd Z, W, F, Ub, Vb;  // B0^-1 U; core solve of the border columns; border rows; U, V by position
  Eigen::PartialPivLU<Eigen::MatrixXd> cap, schur, full;
  bool dense = true;       // the last setup factored densely (or none yet)
  bool next_same = false;  // banded_lowrank_same_but_diagonal was called since the last setup
  int misses = 0;          // setups in a row whose matrix was not band + low rank
  int untested = 0;        // setups still to factor densely without looking for the form
  Eigen::VectorXd xc, xb;
  BandedLowRankStats stats;
  long last_flag = 0;
  ~Content() {
    if (band_ls) SUNLinSolFree(band_ls);
    if (band) SUNMatDestroy(band);
    if (work) N_VDestroy(work);
  }
};

Content* content(SUNLinearSolver s) { return direct_content<Content>(s); }

void layout(Content& c, int n) {
  c.n = n;
  if (static_cast<int>(c.st.cls.size()) != n) c.st.cls.assign(n, -1), c.st.group.assign(n, -1), c.st.groups = 0;
  c.core.clear(), c.border.clear();
  for (int i = 0; i < n; ++i) (c.st.cls[i] >= 0 ? c.core : c.border).push_back(i);
  // class-major: the states of class i of every group side by side
  std::stable_sort(c.core.begin(), c.core.end(), [&](int a, int b) { return c.st.cls[a] < c.st.cls[b]; });
  c.nc = static_cast<int>(c.core.size());
  c.pos.assign(n, -1);
  for (int p = 0; p < c.nc; ++p) c.pos[c.core[p]] = p;
  c.members.assign(c.st.groups, {});
  for (int i = 0; i < n; ++i)
    if (c.st.group[i] >= 0) c.members[c.st.group[i]].push_back(i);
  c.u.assign(n, 0.0), c.v.assign(n, 0.0);
}

bool pivots_ok(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu) {
  if (lu.rows() == 0) return true;
  const auto d = lu.matrixLU().diagonal();
  return d.allFinite() && d.cwiseAbs().minCoeff() > 0.0;
}

// The outer product u v^T of group g from its entries between distant classes (|class i - class j| > reach): u from
// the column q of the largest such entry (and, for the rows near q, from a second column q2 far from both), v from
// its row p (and a second row p2). Returns false when no entries are that far apart to read it from.
bool outer_product(Content& c, const double* a, int g) {
  const auto& m = c.members[g];
  const auto& cls = c.st.cls;
  const int n = c.n, r = c.st.reach;
  auto A = [&](int i, int j) { return a[size_t(j) * n + i]; };
  auto far = [&](int i, int j, int d) { return std::abs(cls[i] - cls[j]) > d; };
  int p = -1, q = -1;
  double amax = 0.0;
  for (int j : m)
    for (int i : m)
      if (far(i, j, r) && std::abs(A(i, j)) > amax) amax = std::abs(A(i, j)), p = i, q = j;
  for (int i : m) c.u[i] = c.v[i] = 0.0;
  if (amax == 0.0) return true;  // no outer product
  int p2 = -1, q2 = -1;
  double best_row = 0.0, best_col = 0.0;
  for (int k : m) {
    if (far(p, k, r) && far(q, k, 2 * r) && std::abs(A(p, k)) > best_col) best_col = std::abs(A(p, k)), q2 = k;
    if (far(k, q, r) && far(k, p, 2 * r) && std::abs(A(k, q)) > best_row) best_row = std::abs(A(k, q)), p2 = k;
  }
  if (q2 < 0 || p2 < 0) return false;
  const double apq = A(p, q), s = apq / A(p, q2);
  for (int i : m) c.u[i] = far(i, q, r) ? A(i, q) : A(i, q2) * s;
  for (int j : m) c.v[j] = far(p, j, r) ? A(p, j) / apq : A(p2, j) / A(p2, q);
  return true;
}

// One pass over the core columns: the largest entry of a group's block left once its outer product is taken off,
// between classes further apart than the reach (relative to the largest entry there), and the band the rest needs
// in the class-major order (entries of a group's block at round-off of its outer product, within the reach, need
// none: the scheme's stencil sets the band, not the reach).
double scan(Content& c, const double* a, int& ml, int& mu) {
  const int n = c.n, r = c.st.reach;
  ml = mu = 0;
  double worst = 0.0, amax = 0.0;
  std::vector<double> scale(c.st.groups, 0.0);
  for (int g = 0; g < c.st.groups; ++g)
    for (int i : c.members[g]) scale[g] = std::max(scale[g], std::abs(c.u[i]));
  double vmax = 0.0;
  for (int i = 0; i < n; ++i) vmax = std::max(vmax, std::abs(c.v[i]));
  for (int pj = 0; pj < c.nc; ++pj) {
    const int j = c.core[pj], gj = c.st.group[j];
    const double* col = a + size_t(j) * n;
    const double vj = c.v[j], cut = gj >= 0 ? kOutsideTol * scale[gj] * vmax : 0.0;
    for (int pi = 0; pi < c.nc; ++pi) {
      const int i = c.core[pi];
      double x = col[i];
      if (gj >= 0 && c.st.group[i] == gj) {
        const double left = std::abs(x - c.u[i] * vj);
        if (std::abs(c.st.cls[i] - c.st.cls[j]) > r) {
          amax = std::max(amax, std::abs(x));
          worst = std::max(worst, left);
          continue;
        }
        if (left <= cut && i != j) continue;
      }
      if (x != 0.0) ml = std::max(ml, pi - pj), mu = std::max(mu, pj - pi);
    }
  }
  return amax > 0.0 ? worst / amax : 0.0;
}

// x (core positions) <- (B0 + U V^T)^-1 x
void core_solve(Content& c, double* x) {
  double* w = N_VGetArrayPointer(c.work);
  std::copy(x, x + c.nc, w);
  SUNLinSolSolve(c.band_ls, c.band, c.work, c.work, 0.0);
  std::copy(w, w + c.nc, x);
  if (c.Ub.cols() == 0) return;
  Eigen::Map<Eigen::VectorXd> xv(x, c.nc);
  const Eigen::VectorXd t = c.cap.solve(c.Vb.transpose() * xv);
  xv -= c.Z * t;
}

// `same`: the matrix is the last one's but for its diagonal (a kept Jacobian at a new cj), so the outer products and
// the band found then still hold.
bool banded_setup(Content& c, const double* a, bool same) {
  const int n = c.n, nc = c.nc, k = static_cast<int>(c.border.size());
  int ml = c.stats.lower, mu = c.stats.upper;
  if (!same) {
    c.terms.clear();
    for (int g = 0; g < c.st.groups; ++g) {
      if (!outer_product(c, a, g)) return false;
      for (int i : c.members[g])
        if (c.u[i] != 0.0) {
          c.terms.push_back(g);
          break;
        }
    }
    c.stats.worst_outside = scan(c, a, ml, mu);
    if (!(c.stats.worst_outside <= kOutsideTol) || ml > nc / 4 || mu > nc / 4) return false;
  }
  if (ml > c.ml || mu > c.mu || !c.band) {  // grows only: a wider band still holds a narrower one
    if (c.band_ls) SUNLinSolFree(c.band_ls);
    if (c.band) SUNMatDestroy(c.band);
    c.ml = std::max(ml, c.ml), c.mu = std::max(mu, c.mu);
    c.band = SUNBandMatrix(nc, c.mu, c.ml, c.ctx);
    c.band_ls = SUNLinSol_Band(c.work, c.band, c.ctx);
    SUNLinSolInitialize(c.band_ls);
  }
  SUNMatZero(c.band);
  for (int pj = 0; pj < nc; ++pj) {
    const int j = c.core[pj], gj = c.st.group[j];
    const double* col = a + size_t(j) * n;
    realtype* bc = SUNBandMatrix_Column(c.band, pj);
    for (int pi = std::max(0, pj - c.mu); pi <= std::min(nc - 1, pj + c.ml); ++pi) {
      const int i = c.core[pi];
      bc[pi - pj] = gj >= 0 && c.st.group[i] == gj ? col[i] - c.u[i] * c.v[j] : col[i];
    }
  }
  if (SUNLinSolSetup(c.band_ls, c.band) != 0) return false;
  const int rk = static_cast<int>(c.terms.size());
  c.Ub.setZero(nc, rk), c.Vb.setZero(nc, rk);
  for (int t = 0; t < rk; ++t)
    for (int i : c.members[c.terms[t]]) c.Ub(c.pos[i], t) = c.u[i], c.Vb(c.pos[i], t) = c.v[i];
  if (rk > 0) {
    c.Z = c.Ub;
    Eigen::MatrixXd none;
    std::swap(none, c.Ub);  // core_solve without the outer products while Z is formed
    for (int t = 0; t < rk; ++t) core_solve(c, c.Z.col(t).data());
    std::swap(none, c.Ub);
    c.cap.compute(Eigen::MatrixXd::Identity(rk, rk) + c.Vb.transpose() * c.Z);
    if (!pivots_ok(c.cap)) return false;
  }
  // the border: E (core rows, border columns), F (border rows, core columns), C; Schur complement C - F B^-1 E
  c.W.resize(nc, k), c.F.resize(k, nc);
  Eigen::MatrixXd C(k, k);
  for (int b = 0; b < k; ++b) {
    const double* col = a + size_t(c.border[b]) * n;
    for (int p = 0; p < nc; ++p) c.W(p, b) = col[c.core[p]];
    for (int b2 = 0; b2 < k; ++b2) C(b2, b) = col[c.border[b2]];
    if (!c.W.col(b).isZero(0.0)) core_solve(c, c.W.col(b).data());  // a border state no class reads
  }
  for (int p = 0; p < nc; ++p) {
    const double* col = a + size_t(c.core[p]) * n;
    for (int b = 0; b < k; ++b) c.F(b, p) = col[c.border[b]];
  }
  c.schur.compute(C - c.F * c.W);
  c.stats.lower = ml, c.stats.upper = mu, c.stats.border = k, c.stats.rank = rk;
  return pivots_ok(c.schur) && c.Z.allFinite() && c.W.allFinite();
}

int setup(SUNLinearSolver s, SUNMatrix a) {
  Content& c = *content(s);
  const int n = static_cast<int>(SUNDenseMatrix_Rows(a));
  if (n != c.n) {
    layout(c, n);
    if (c.work) N_VDestroy(c.work);
    c.work = N_VNew_Serial(std::max(c.nc, 1), c.ctx);
  }
  const double* data = SUNDenseMatrix_Data(a);
  ++c.stats.setups;
  c.stats.states = n;
  const bool same = c.next_same && !c.dense && c.stats.setups > 1;
  c.next_same = false;
  // A matrix that was not of the form at kMissesBeforeSkip setups in a row (an aggregation kernel couples every class
  // pair: the headline scene above 400 unknowns, which `auto` hands this solver) is factored densely without the test
  // for the next kUntestedSetups setups: the test, a scan of the whole matrix, cost 6 % of such a run.
  if (c.untested > 0) {
    --c.untested;
    ++c.stats.untested_setups;
    c.dense = true;
  } else {
    c.dense = c.nc == 0 || !banded_setup(c, data, same);
    c.misses = c.dense ? c.misses + 1 : 0;
    if (c.misses >= kMissesBeforeSkip) c.untested = kUntestedSetups, c.misses = 0;
  }
  bool ok = true;
  if (c.dense) {  // not of the form (or a zero pivot in the band): the whole matrix
    ++c.stats.dense_setups;
    c.full.compute(Eigen::Map<const Eigen::MatrixXd>(data, n, n));
    ok = pivots_ok(c.full);
  }
  c.last_flag = ok ? 0 : 1;  // a zero pivot: the integrator retries with a smaller step
  return static_cast<int>(c.last_flag);
}

int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  Content& c = *content(s);
  const int n = c.n, nc = c.nc, k = static_cast<int>(c.border.size());
  const double* bv = N_VGetArrayPointer(b);
  double* xv = N_VGetArrayPointer(x);
  if (c.dense) {
    Eigen::Map<Eigen::VectorXd>(xv, n) = c.full.solve(Eigen::Map<const Eigen::VectorXd>(bv, n));
  } else {
    c.xc.resize(nc), c.xb.resize(k);
    for (int p = 0; p < nc; ++p) c.xc[p] = bv[c.core[p]];
    for (int q = 0; q < k; ++q) c.xb[q] = bv[c.border[q]];
    core_solve(c, c.xc.data());
    if (k > 0) {
      c.xb = c.schur.solve(c.xb - c.F * c.xc);
      c.xc -= c.W * c.xb;
    }
    for (int p = 0; p < nc; ++p) xv[c.core[p]] = c.xc[p];
    for (int q = 0; q < k; ++q) xv[c.border[q]] = c.xb[q];
  }
  bool finite = true;
  for (int i = 0; i < n; ++i) finite = finite && std::isfinite(xv[i]);
  return static_cast<int>(c.last_flag = finite ? 0 : 1);
}

}  // namespace

SUNLinearSolver make_banded_lowrank_solver(SUNContext ctx, ClassStructure st) {
  auto c = std::make_unique<Content>();
  c->st = std::move(st);
  c->ctx = ctx;
  return new_direct_solver(ctx, std::move(c), setup, solve);
}

bool is_banded_lowrank_solver(SUNLinearSolver s) { return s && s->ops->setup == setup; }

void banded_lowrank_same_but_diagonal(SUNLinearSolver s) { content(s)->next_same = true; }

void banded_lowrank_new_segment(SUNLinearSolver s) {
  Content& c = *content(s);
  c.misses = c.untested = 0;
}

BandedLowRankStats banded_lowrank_stats(SUNLinearSolver s) { return content(s)->stats; }

}  // namespace granuflow::detail
