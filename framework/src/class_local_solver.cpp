#include "class_local_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "direct_linear_solver.hpp"
#include "granuflow/dae_system.hpp"

namespace granuflow::detail {

namespace {

struct Content {
  ClassLocalSource src;
  int n = 0;
  std::vector<int> start;    // per class, its first position among the core states (one more entry at the end)
  std::vector<int> members;  // the core states by position: class by class, ascending within a class
  std::vector<int> border;   // the states that are not per class
  std::vector<size_t> at;    // per class, where its block starts in `lu`
  std::vector<double> lu;    // the blocks' LU factors, each column-major, one after the other
  std::vector<double> inv;   // the blocks' inverses, laid out alike (from their LU)
  std::vector<double> rinv;  // per position, 1 / U's diagonal entry
  std::vector<int> piv;      // per position, the row of its block swapped with it (block-relative)
  Eigen::MatrixXd W, F;      // B^-1 E (core rows x border columns); border rows x core columns
  Eigen::PartialPivLU<Eigen::MatrixXd> schur, full;
  Eigen::VectorXd xc, xb, tb;
  // Conservation: per conserved block g, u_g (1/size on its rows) and s_g (the column sums over its rows of every
  // entry the class-local matrix B lacks); B + U S^T by Sherman-Morrison-Woodbury, Z = B^-1 U.
  Eigen::MatrixXd U, S, Z;
  Eigen::PartialPivLU<Eigen::MatrixXd> cap;
  Eigen::VectorXd t;
  bool whole = false;      // asked to factor the whole matrix (consistent initial values)
  bool whole_now = false;  // the last setup did
  bool next_same = false;  // class_local_same_but_diagonal was called since the last setup
  bool pairs = false;      // every block holds two states
  ClassLocalStats stats;
  long last_flag = 0;
};

Content* content(SUNLinearSolver s) { return direct_content<Content>(s); }

constexpr int kMaxBlockOnStack = 16;  // blocks up to this many states are applied as inverses

void layout(Content& c, int n) {
  c.n = n;
  if (static_cast<int>(c.src.st.cls.size()) != n) c.src.st.cls.assign(n, -1);
  int classes = 0;
  for (int i = 0; i < n; ++i) classes = std::max(classes, c.src.st.cls[i] + 1);
  c.start.assign(classes + 1, 0);
  c.border.clear();
  for (int i = 0; i < n; ++i)
    if (c.src.st.cls[i] >= 0)
      ++c.start[c.src.st.cls[i] + 1];
    else
      c.border.push_back(i);
  for (int k = 0; k < classes; ++k) c.start[k + 1] += c.start[k];
  c.members.assign(c.start[classes], 0);
  std::vector<int> next(c.start.begin(), c.start.end() - 1);
  for (int i = 0; i < n; ++i)
    if (c.src.st.cls[i] >= 0) c.members[next[c.src.st.cls[i]]++] = i;
  c.at.assign(classes + 1, 0);
  int largest = 0;
  for (int k = 0; k < classes; ++k) {
    const int b = c.start[k + 1] - c.start[k];
    largest = std::max(largest, b);
    c.at[k + 1] = c.at[k] + size_t(b) * b;
  }
  c.lu.assign(c.at[classes], 0.0);
  c.inv.assign(c.at[classes], 0.0);
  c.rinv.assign(c.members.size(), 0.0);
  c.piv.assign(c.members.size(), 0);
  c.stats.classes = classes, c.stats.largest_block = largest;
  c.pairs = classes > 0 && c.members.size() == 2 * size_t(classes);
  c.stats.border = static_cast<int>(c.border.size()), c.stats.states = n;
}

// The blocks hold a few states each (a bed's mass and water of one class): Eigen's dynamic-size LU would cost more
// in per-call overhead than their arithmetic, a hundred blocks per solve, so they are factored here, LAPACK's way
// (row interchanges on whole rows, L unit lower triangular below U). False on a zero or non-finite pivot.
bool factor_block(double* a, int b, int* piv, double* rinv) {
  for (int k = 0; k < b; ++k) {
    double* ck = a + size_t(k) * b;
    int q = k;
    for (int i = k + 1; i < b; ++i)
      if (std::abs(ck[i]) > std::abs(ck[q])) q = i;
    piv[k] = q;
    if (!(std::abs(ck[q]) > 0.0) || !std::isfinite(ck[q])) return false;
    if (q != k)
      for (int j = 0; j < b; ++j) std::swap(a[size_t(j) * b + k], a[size_t(j) * b + q]);
    rinv[k] = 1.0 / ck[k];
    for (int i = k + 1; i < b; ++i) ck[i] *= rinv[k];
    for (int j = k + 1; j < b; ++j) {
      double* cj = a + size_t(j) * b;
      for (int i = k + 1; i < b; ++i) cj[i] -= ck[i] * cj[k];
    }
  }
  return true;
}

void solve_block(const double* a, int b, const int* piv, const double* rinv, double* x) {
  for (int k = 0; k < b; ++k) std::swap(x[k], x[piv[k]]);  // P^T x, every interchange before L
  for (int k = 0; k < b; ++k) {
    const double* ck = a + size_t(k) * b;
    for (int i = k + 1; i < b; ++i) x[i] -= ck[i] * x[k];
  }
  for (int k = b - 1; k >= 0; --k) {
    x[k] *= rinv[k];
    const double* ck = a + size_t(k) * b;
    for (int i = 0; i < k; ++i) x[i] -= ck[i] * x[k];
  }
}

// x (core positions) <- B^-1 x, B the block diagonal: each block's inverse times its part of x. A solve runs once
// per Newton iteration and per border column and conservation term of each setup; the blocks are a few states each
// and well conditioned (the Newton matrix's diagonal dominates within a class), so their inverses, formed once per
// setup from the LU, cost a few multiplications where the LU's substitutions cost a chain of dependent ones.
void solve_blocks(const Content& c, double* x) {
  if (c.pairs) {  // every class a pair of states (a bed's mass and water): the loop the compiler vectorizes
    const double* a = c.inv.data();
    const int m = static_cast<int>(c.start.size()) - 1;
#pragma omp simd
    for (int k = 0; k < m; ++k) {
      const double x0 = x[2 * k], x1 = x[2 * k + 1];
      x[2 * k] = a[4 * k] * x0 + a[4 * k + 2] * x1;
      x[2 * k + 1] = a[4 * k + 1] * x0 + a[4 * k + 3] * x1;
    }
    return;
  }
  double y[kMaxBlockOnStack];
  for (size_t k = 0; k + 1 < c.start.size(); ++k) {
    const int p = c.start[k], b = c.start[k + 1] - p;
    const double* a = c.inv.data() + c.at[k];
    if (b > kMaxBlockOnStack) {  // a flowsheet with many units per class: the substitutions, in place
      solve_block(c.lu.data() + c.at[k], b, c.piv.data() + p, c.rinv.data() + p, x + p);
      continue;
    }
    for (int i = 0; i < b; ++i) y[i] = 0.0;
    for (int j = 0; j < b; ++j)
      for (int i = 0; i < b; ++i) y[i] += a[size_t(j) * b + i] * x[p + j];
    for (int i = 0; i < b; ++i) x[p + i] = y[i];
  }
}

bool pivots_ok(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu) {
  if (lu.rows() == 0) return true;
  const auto d = lu.matrixLU().diagonal();
  return d.allFinite() && d.cwiseAbs().minCoeff() > 0.0;
}

// The class blocks, then the border by its Schur complement C - F B^-1 E; the entries between classes are not read.
bool factor_local(Content& c, const double* m) {
  const int n = c.n, k = static_cast<int>(c.border.size()), nc = static_cast<int>(c.members.size());
  auto A = [m, n](int i, int j) { return m[size_t(j) * n + i]; };
  for (size_t cl = 0; cl + 1 < c.start.size(); ++cl) {
    const int p0 = c.start[cl], b = c.start[cl + 1] - p0;
    double* blk = c.lu.data() + c.at[cl];
    for (int q = 0; q < b; ++q)
      for (int p = 0; p < b; ++p) blk[size_t(q) * b + p] = A(c.members[p0 + p], c.members[p0 + q]);
    if (!factor_block(blk, b, c.piv.data() + p0, c.rinv.data() + p0)) return false;
    double* inv = c.inv.data() + c.at[cl];
    for (int j = 0; j < b; ++j) {  // column j of the inverse: the block's solve of the unit vector e_j
      for (int i = 0; i < b; ++i) inv[size_t(j) * b + i] = i == j ? 1.0 : 0.0;
      solve_block(blk, b, c.piv.data() + p0, c.rinv.data() + p0, inv + size_t(j) * b);
    }
  }
  c.W.resize(nc, k), c.F.resize(k, nc);
  Eigen::MatrixXd C(k, k);
  for (int b = 0; b < k; ++b) {
    for (int p = 0; p < nc; ++p) c.W(p, b) = A(c.members[p], c.border[b]);
    for (int b2 = 0; b2 < k; ++b2) C(b2, b) = A(c.border[b2], c.border[b]);
    solve_blocks(c, c.W.col(b).data());
  }
  for (int p = 0; p < nc; ++p)
    for (int b = 0; b < k; ++b) c.F(b, p) = A(c.border[b], c.members[p]);
  if (k > 0) c.schur.compute(C - c.F * c.W);
  return (k == 0 || pivots_ok(c.schur)) && c.W.allFinite();
}

// x <- B^-1 b over all unknowns (x and b may be one vector)
void solve_local(Content& c, const double* b, double* x) {
  const int k = static_cast<int>(c.border.size()), nc = static_cast<int>(c.members.size());
  c.xc.resize(nc), c.xb.resize(k), c.tb.resize(k);
  for (int p = 0; p < nc; ++p) c.xc[p] = b[c.members[p]];
  for (int q = 0; q < k; ++q) c.tb[q] = b[c.border[q]];
  solve_blocks(c, c.xc.data());
  if (k > 0) {
    c.tb.noalias() -= c.F * c.xc;
    c.xb = c.schur.solve(c.tb);
    c.xc.noalias() -= c.W * c.xb;
  }
  for (int p = 0; p < nc; ++p) x[c.members[p]] = c.xc[p];
  for (int q = 0; q < k; ++q) x[c.border[q]] = c.xb[q];
}

// The conservation terms: without them a Newton correction would move a block's total (the pair terms' entries
// between classes are what moves mass and water between classes, and they sum to zero over the block), so a run
// conserved solids to 1e-6 instead of 1e-15 at 80 classes. `same`: the matrix is the last one's but on the
// diagonal, which is within a class: S and U hold.
bool conservation_setup(Content& c, const double* m, bool same) {
  const auto& blocks = c.src.blocks;
  const int n = c.n, G = static_cast<int>(blocks.size());
  if (G == 0) return true;
  if (!same || c.S.rows() != n) {
    c.U.setZero(n, G), c.S.setZero(n, G);
    for (int g = 0; g < G; ++g) {
      const double* left = c.src.left_out ? c.src.left_out(g) : nullptr;
      for (int col = 0; col < n; ++col) {
        double sum = left ? left[col] : 0.0;
        const int cc = c.src.st.cls[col];
        if (cc >= 0)
          for (int r : blocks[g])
            if (c.src.st.cls[r] != cc) sum += m[size_t(col) * n + r];
        c.S(col, g) = sum;
      }
      // u_g: the block's content by class (what the left-out births and deaths move is there), evenly if empty
      const double* y = c.src.at ? c.src.at() : nullptr;
      double total = 0.0;
      for (int r : blocks[g]) total += y ? std::max(y[r], 0.0) : 0.0;
      for (int r : blocks[g]) c.U(r, g) = total > 0.0 ? std::max(y[r], 0.0) / total : 1.0 / double(blocks[g].size());
    }
  }
  c.Z.resize(n, G);
  for (int g = 0; g < G; ++g) solve_local(c, c.U.col(g).data(), c.Z.col(g).data());
  c.cap.compute(Eigen::MatrixXd::Identity(G, G) + c.S.transpose() * c.Z);
  return pivots_ok(c.cap) && c.Z.allFinite();
}

int setup(SUNLinearSolver s, SUNMatrix a) {
  Content& c = *content(s);
  const int n = static_cast<int>(SUNDenseMatrix_Rows(a));
  if (n != c.n) layout(c, n);
  const double* m = SUNDenseMatrix_Data(a);
  ++c.stats.setups;
  const bool same = c.next_same && !c.whole_now && c.stats.setups > 1;
  c.next_same = false;
  c.whole_now = c.whole || c.members.empty();
  bool ok = true;
  if (c.whole_now) {
    ++c.stats.whole_setups;
    c.full.compute(Eigen::Map<const Eigen::MatrixXd>(m, n, n));
    ok = pivots_ok(c.full);
  } else {
    ok = factor_local(c, m) && conservation_setup(c, m, same);
  }
  c.last_flag = ok ? 0 : 1;  // a zero pivot: the integrator retries with a smaller step
  return static_cast<int>(c.last_flag);
}

int solve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  Content& c = *content(s);
  const int n = c.n;
  const double* bv = N_VGetArrayPointer(b);
  double* xv = N_VGetArrayPointer(x);
  if (c.whole_now) {
    Eigen::Map<Eigen::VectorXd>(xv, n) = c.full.solve(Eigen::Map<const Eigen::VectorXd>(bv, n));
  } else {
    solve_local(c, bv, xv);
    if (c.Z.cols() > 0) {  // (B + U S^T)^-1 b = x - Z (I + S^T Z)^-1 S^T x
      Eigen::Map<Eigen::VectorXd> x(xv, n);
      c.t = c.cap.solve(c.S.transpose() * x);
      x.noalias() -= c.Z * c.t;
    }
  }
  bool finite = true;
  for (int i = 0; i < n; ++i) finite = finite && std::isfinite(xv[i]);
  return static_cast<int>(c.last_flag = finite ? 0 : 1);
}

}  // namespace

ClassLocalSource class_local_source(const DaeSystem& sys) {
  return {class_structure(sys), sys.conserved_blocks(), [&sys](int block) { return sys.left_out(block); },
          [&sys] { return sys.left_out_at(); }};
}

SUNLinearSolver make_class_local_solver(SUNContext ctx, ClassLocalSource src) {
  auto c = std::make_unique<Content>();
  c->src = std::move(src);
  return new_direct_solver(ctx, std::move(c), setup, solve);
}

bool is_class_local_solver(SUNLinearSolver s) { return s && s->ops->setup == setup; }

void class_local_whole(SUNLinearSolver s, bool whole) { content(s)->whole = whole; }

void class_local_same_but_diagonal(SUNLinearSolver s) { content(s)->next_same = true; }

ClassLocalStats class_local_stats(SUNLinearSolver s) { return content(s)->stats; }

}  // namespace granuflow::detail
