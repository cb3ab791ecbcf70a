#include "eigen_linear_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "direct_linear_solver.hpp"

namespace granuflow::detail {
namespace {

struct Content {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;  // the whole matrix (one group, or one that holds nearly every state)
  std::vector<std::vector<int>> groups;     // more than one: the states of each independent group
  std::vector<int> group_of;                // with groups: each state's group
  std::vector<std::vector<int>> holes;      // with groups: the states inside each group's span that are not in it
  struct Run {
    int pos, state, len;  // the group's states pos .. pos+len-1 are the consecutive states state .. state+len-1
  };
  std::vector<std::vector<Run>> runs;  // with groups: each group's states as runs of consecutive states
  bool split = false;                  // factored group by group
  long unsplit_setups = 0;             // setups since the groups were last looked for, while not split
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXd>> group_lu;
  std::vector<int> parent;
  Eigen::MatrixXd sub;
  Eigen::VectorXd rhs;
  long last_flag = 0;
};

int root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The connected components of the nonzero pattern of m (rows and columns joined by every nonzero off the diagonal),
// each as its sorted states; one component leaves `groups` empty.
void find_groups(const Eigen::Map<const Eigen::MatrixXd>& m, Content& c) {
  const int n = static_cast<int>(m.rows());
  c.parent.resize(n);
  for (int i = 0; i < n; ++i) c.parent[i] = i;
  int count = n;  // components so far: a coupled matrix stops the scan as soon as it is one
  for (int j = 0; j < n && count > 1; ++j) {
    const double* col = m.data() + size_t(j) * n;
    // The root of j's component, kept through the unions below: a loose state (no coupling at all) keeps count
    // above 1, and the scan then reads every entry.
    int b = root(c.parent, j);
    for (int i = 0; i < n; ++i)
      if (col[i] != 0.0 && i != j) {
        const int a = root(c.parent, i);
        if (a != b) c.parent[std::max(a, b)] = std::min(a, b), b = std::min(a, b), --count;
      }
  }
  c.groups.clear();
  if (count == 1) return;
  std::vector<int> slot(n, -1);
  c.group_of.resize(n);
  for (int i = 0; i < n; ++i) {
    int& g = slot[root(c.parent, i)];
    if (g < 0) g = static_cast<int>(c.groups.size()), c.groups.emplace_back();
    c.groups[g].push_back(i);
    c.group_of[i] = g;
  }
  c.holes.assign(c.groups.size(), {});
  for (size_t g = 0; g < c.groups.size(); ++g)
    for (int i = c.groups[g].front(); i < c.groups[g].back(); ++i)
      if (c.group_of[i] != static_cast<int>(g)) c.holes[g].push_back(i);
  c.runs.assign(c.groups.size(), {});
  for (size_t g = 0; g < c.groups.size(); ++g) {
    const auto& idx = c.groups[g];
    for (int p = 0; p < static_cast<int>(idx.size()); ++p)
      if (p > 0 && idx[p] == idx[p - 1] + 1)
        ++c.runs[g].back().len;
      else
        c.runs[g].push_back({p, idx[p], 1});
  }
}

size_t largest_group(const Content& c) {
  size_t largest = 0;
  for (const auto& g : c.groups) largest = std::max(largest, g.size());
  return largest;
}

// Splitting pays when no group holds nearly every state (a group of 90 % still costs 73 % of the whole LU; the whole
// matrix keeps the factorization, and so the results, of a coupled flowsheet with a few loose states).
bool split_pays(const Content& c, long n) { return c.groups.size() > 1 && double(largest_group(c)) <= 0.9 * double(n); }

// Whether the groups of the last setup still separate m (no nonzero joins two of them): a scan without the
// union-find, and the structure rarely changes between setups.
bool groups_hold(const Eigen::Map<const Eigen::MatrixXd>& m, const Content& c) {
  const int n = static_cast<int>(m.rows());
  if (c.groups.empty() || static_cast<int>(c.group_of.size()) != n) return false;
  // Per group, its columns must be zero above and below its span and on the few states inside the span that belong
  // to other groups: plain scans without a look-up per entry (the same entries as testing every row's group).
  for (size_t g = 0; g < c.groups.size(); ++g) {
    const int lo = c.groups[g].front(), hi = c.groups[g].back() + 1;
    for (int j : c.groups[g]) {
      const double* col = m.data() + size_t(j) * n;
      bool nonzero = false;
      for (int i = 0; i < lo; ++i) nonzero |= col[i] != 0.0;
      for (int i = hi; i < n; ++i) nonzero |= col[i] != 0.0;
      for (int i : c.holes[g]) nonzero |= col[i] != 0.0;
      if (nonzero) return false;
    }
  }
  return true;
}

bool pivots_ok(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu) {
  const auto diag = lu.matrixLU().diagonal();
  return diag.allFinite() && diag.cwiseAbs().minCoeff() > 0.0;
}

Content* content(SUNLinearSolver s) { return direct_content<Content>(s); }

int setup(SUNLinearSolver s, SUNMatrix a) {
  const auto n = SUNDenseMatrix_Rows(a);
  Eigen::Map<const Eigen::MatrixXd> m(SUNDenseMatrix_Data(a), n, n);  // column-major, like SUNDenseMatrix
  Content& c = *content(s);
  // Looking for groups reads all n^2 entries, as much as half of a small LU: a split factorization checks on every
  // setup that its groups still hold (it would be wrong otherwise), a whole one looks again only every 16th setup
  // (missing a split costs time, never accuracy).
  const bool look = c.split ? !groups_hold(m, c) : c.unsplit_setups++ % 16 == 0;
  if (look) {
    find_groups(m, c);
    c.split = split_pays(c, n);
    c.unsplit_setups = c.split ? 0 : 1;
  }
  // A zero or non-finite pivot makes the step fail recoverably: the integrator retries with a smaller step.
  // (A condition estimate would cost as much as a third of the factorization.)
  bool ok = true;
  if (!c.split) {
    c.lu.compute(m);
    ok = pivots_ok(c.lu);
  } else {
    c.group_lu.resize(c.groups.size());
    for (size_t g = 0; g < c.groups.size(); ++g) {
      const auto& idx = c.groups[g];
      const int k = static_cast<int>(idx.size());
      c.sub.resize(k, k);
      for (int j = 0; j < k; ++j)  // the group's entries of column idx[j], copied run by run
        for (const auto& r : c.runs[g]) c.sub.col(j).segment(r.pos, r.len) = m.col(idx[j]).segment(r.state, r.len);
      c.group_lu[g].compute(c.sub);
      ok = ok && pivots_ok(c.group_lu[g]);
    }
  }
  c.last_flag = ok ? 0 : 1;
  return static_cast<int>(c.last_flag);
}

int solve(SUNLinearSolver s, SUNMatrix a, N_Vector x, N_Vector b, realtype) {
  const auto n = SUNDenseMatrix_Rows(a);
  Content& c = *content(s);
  Eigen::Map<const Eigen::VectorXd> bv(N_VGetArrayPointer(b), n);
  Eigen::Map<Eigen::VectorXd> xv(N_VGetArrayPointer(x), n);
  if (!c.split) {
    xv = c.lu.solve(bv);
  } else {
    for (size_t g = 0; g < c.groups.size(); ++g) {  // x and b may be one vector: each group reads its b first
      const auto& idx = c.groups[g];
      const int k = static_cast<int>(idx.size());
      c.rhs.resize(k);
      for (int i = 0; i < k; ++i) c.rhs[i] = bv[idx[i]];
      c.rhs = c.group_lu[g].solve(c.rhs);
      for (int i = 0; i < k; ++i) xv[idx[i]] = c.rhs[i];
    }
  }
  if (!xv.allFinite()) return c.last_flag = 1;
  return c.last_flag = 0;
}

}  // namespace

int eigen_dense_groups(SUNLinearSolver s) {
  return content(s)->split ? static_cast<int>(content(s)->groups.size()) : 1;
}

int eigen_dense_largest_block(SUNLinearSolver s) {
  const Content& c = *content(s);
  return static_cast<int>(c.split ? largest_group(c) : c.lu.rows());
}

int eigen_dense_block_for(const double* a, int n) {
  Content c;
  find_groups(Eigen::Map<const Eigen::MatrixXd>(a, n, n), c);
  return split_pays(c, n) ? static_cast<int>(largest_group(c)) : n;
}

SUNLinearSolver make_eigen_dense_solver(SUNContext ctx) {
  return new_direct_solver(ctx, std::make_unique<Content>(), setup, solve);
}

}  // namespace granuflow::detail
