#include "granuflow/structure.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <set>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"

namespace granuflow {

Matching maximum_matching(int n_cols, const std::vector<std::vector<int>>& adj) {
  const int n_rows = static_cast<int>(adj.size());
  constexpr int kInf = std::numeric_limits<int>::max();
  Matching m;
  m.row_col.assign(n_rows, -1);
  m.col_row.assign(n_cols, -1);
  std::vector<int> dist(n_rows);
  // Phase: BFS layers from the free rows; a shortest augmenting path ends at a free column.
  auto bfs = [&] {
    std::queue<int> q;
    bool found = false;
    for (int r = 0; r < n_rows; ++r) {
      dist[r] = m.row_col[r] < 0 ? 0 : kInf;
      if (dist[r] == 0) q.push(r);
    }
    while (!q.empty()) {
      const int r = q.front();
      q.pop();
      for (int c : adj[r]) {
        const int r2 = m.col_row[c];
        if (r2 < 0)
          found = true;
        else if (dist[r2] == kInf)
          dist[r2] = dist[r] + 1, q.push(r2);
      }
    }
    return found;
  };
  // Vertex-disjoint augmenting paths along the layers, by an explicit stack (paths can be as long as the
  // system is large, too deep for recursion).
  std::vector<size_t> next(n_rows);
  auto augment = [&](int root) {
    std::vector<int> path{root};
    while (!path.empty()) {
      const int r = path.back();
      if (next[r] == adj[r].size()) {
        dist[r] = kInf;  // dead end in this phase
        path.pop_back();
        continue;
      }
      const int c = adj[r][next[r]++];
      const int r2 = m.col_row[c];
      if (r2 < 0) {  // free column: flip the path
        int col = c;
        for (int k = static_cast<int>(path.size()) - 1; k >= 0; --k) {
          const int row = path[k];
          const int prev = m.row_col[row];
          m.row_col[row] = col;
          m.col_row[col] = row;
          col = prev;
        }
        return true;
      }
      if (dist[r2] == dist[r] + 1) path.push_back(r2);
    }
    return false;
  };
  while (bfs()) {
    std::fill(next.begin(), next.end(), 0);
    for (int r = 0; r < n_rows; ++r)
      if (m.row_col[r] < 0 && augment(r)) ++m.size;
  }
  return m;
}

Deficiency structural_deficiency(int n_cols, const std::vector<std::vector<int>>& adj, const Matching& m) {
  const int n_rows = static_cast<int>(adj.size());
  std::vector<std::vector<int>> col_rows(n_cols);
  for (int r = 0; r < n_rows; ++r)
    for (int c : adj[r]) col_rows[c].push_back(r);
  Deficiency d;
  // Under-determined: from each free column to the rows containing it, on to their matched columns.
  std::vector<char> seen_c(n_cols, 0), seen_r(n_rows, 0);
  std::vector<int> stack;
  for (int c = 0; c < n_cols; ++c)
    if (m.col_row[c] < 0) seen_c[c] = 1, stack.push_back(c);
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    d.cols.push_back(c);
    for (int r : col_rows[c]) {
      const int c2 = m.row_col[r];
      if (c2 >= 0 && !seen_c[c2]) seen_c[c2] = 1, stack.push_back(c2);
    }
  }
  // Over-determined: from each free row to its columns, on to their matched rows.
  for (int r = 0; r < n_rows; ++r)
    if (m.row_col[r] < 0) seen_r[r] = 1, stack.push_back(r);
  while (!stack.empty()) {
    const int r = stack.back();
    stack.pop_back();
    d.rows.push_back(r);
    for (int c : adj[r]) {
      const int r2 = m.col_row[c];
      if (r2 >= 0 && !seen_r[r2]) seen_r[r2] = 1, stack.push_back(r2);
    }
  }
  std::sort(d.rows.begin(), d.rows.end());
  std::sort(d.cols.begin(), d.cols.end());
  return d;
}

namespace {

constexpr int kMaxNumericalCheck = 3000;
constexpr size_t kMaxNamed = 12;

// "mixer.T, splitter.T" and "mixer, splitter" for global state indices.
std::pair<std::string, std::string> names(const Flowsheet& fs, const std::vector<int>& states) {
  const auto all = fs.state_names();
  std::string s, u;
  std::set<std::string> units;
  for (size_t k = 0; k < states.size(); ++k) {
    if (k == kMaxNamed) {
      s += " and " + std::to_string(states.size() - kMaxNamed) + " more";
      break;
    }
    s += (s.empty() ? "" : ", ") + all[states[k]];
  }
  for (int g : states) {
    const std::string& name = fs.units()[fs.state_unit(g)].name;
    if (units.insert(name).second) u += (u.empty() ? "" : ", ") + name;
  }
  return {s, u};
}

}  // namespace

namespace {

// The message for `sys`, or nothing if its algebraic equations can be solved at the initial state.
std::optional<std::string> diagnose(DaeSystem& sys, const double* j0) {
  const Flowsheet& fs = sys.flowsheet();
  const int n = sys.size();
  const auto id = sys.differential_id();
  std::vector<int> alg, local(n, -1);
  for (int i = 0; i < n; ++i)
    if (id[i] == 0.0) local[i] = static_cast<int>(alg.size()), alg.push_back(i);
  const int na = static_cast<int>(alg.size());
  if (na == 0) return std::nullopt;

  // dF_a/dy_a at the initial state, with cj = 0 (algebraic rows hold no y'). Rows and columns are indexed
  // alike: the residual of a state is its equation. An inlined system (explicit units eliminated) is solved
  // densely and has no sparse pattern of its own: there the nonzeros of its Jacobian stand for it.
  std::vector<double> y, yp(n, 0.0);
  sys.initial_values(y);
  std::vector<std::vector<int>> adj(na);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(na, na);
  if (sys.inlined()) {
    std::vector<double> j;
    if (j0)
      j.assign(j0, j0 + size_t(n) * n);
    else
      j.resize(size_t(n) * n), sys.jacobian(0.0, y.data(), yp.data(), 0.0, j.data(), nullptr);
    for (int c = 0; c < n; ++c) {
      if (local[c] < 0) continue;
      for (int r = 0; r < n; ++r)
        if (local[r] >= 0 && j[size_t(c) * n + r] != 0.0) {
          adj[local[r]].push_back(local[c]);
          a(local[r], local[c]) = j[size_t(c) * n + r];
        }
    }
  } else {
    const SparsityPattern& p = sys.pattern();
    std::vector<double> v(p.nnz());
    if (na <= kMaxNumericalCheck) sys.jacobian(0.0, y.data(), yp.data(), 0.0, nullptr, v.data());
    for (int c = 0; c < n; ++c) {
      if (local[c] < 0) continue;
      for (int k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k)
        if (local[p.row_idx[k]] >= 0) {
          adj[local[p.row_idx[k]]].push_back(local[c]);
          if (na <= kMaxNumericalCheck) a(local[p.row_idx[k]], local[c]) = v[k];
        }
    }
  }
  const Matching m = maximum_matching(na, adj);
  // Only a true pattern proves a structural defect; the inlined system's stands for one point.
  if (m.size < na && !sys.inlined()) {
    const Deficiency d = structural_deficiency(na, adj, m);
    std::vector<int> cols, rows;
    for (int c : d.cols) cols.push_back(alg[c]);
    for (int r : d.rows) rows.push_back(alg[r]);
    const auto [cs, cu] = names(fs, cols);
    const auto [rs, ru] = names(fs, rows);
    return "flowsheet '" + fs.name() + "' is structurally singular: its algebraic equations can determine " +
           std::to_string(m.size) + " of its " + std::to_string(na) +
           " algebraic states whatever the parameters; no equation is left for " + cs + " (units " + cu +
           "), and the equations of " + rs + " (units " + ru +
           ") over-determine theirs. Check the connections of "
           "these units";
  }
  if (na > kMaxNumericalCheck) return std::nullopt;
  if (!a.allFinite()) return std::nullopt;  // a failing residual is the integrator's to report, with its time and unit
  // Equilibrate rows, then columns, so that the rank does not depend on the states' units.
  for (int r = 0; r < na; ++r)
    if (const double s = a.row(r).cwiseAbs().maxCoeff(); s > 0) a.row(r) /= s;
  for (int c = 0; c < na; ++c)
    if (const double s = a.col(c).cwiseAbs().maxCoeff(); s > 0) a.col(c) /= s;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(a);
  lu.setThreshold(1e-10);
  if (lu.rank() == na) return std::nullopt;
  // The states of the loop: those that move in some direction the equations do not see.
  const Eigen::MatrixXd ker = lu.kernel();
  std::vector<int> loop;
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < ker.cols(); ++j)
      if (std::abs(ker(i, j)) > 1e-3 * ker.col(j).cwiseAbs().maxCoeff()) {
        loop.push_back(alg[i]);
        break;
      }
  const auto [ls, lu_names] = names(fs, loop);
  return "flowsheet '" + fs.name() + "': the algebraic equations cannot be solved for " + ls +
         " at the initial state (units " + lu_names + "; their Jacobian is singular, rank " +
         std::to_string(lu.rank()) + " of " + std::to_string(na) +
         "): an algebraic loop without hold-up, such as a recycle of mixers and splitters that returns all of its "
         "flow? Check the split fractions, or put a unit with hold-up (e.g. a stirred_tank) into the loop" +
         (!sys.inlined() && fs.n_explicit_states() > 0
              ? std::string("; solver: {linear_solver: dense} evaluates explicit units inside the loop instead of "
                            "guessing their states")
              : std::string());
}

}  // namespace

void check_algebraic_structure(DaeSystem& sys, const double* j0) {
  auto message = diagnose(sys, j0);
  if (!message) return;
  // Explicit units are eliminated from an inlined system; the full one names their states too.
  if (sys.inlined()) {
    DaeSystem full(sys.flowsheet(), false);
    if (auto named = diagnose(full, nullptr)) message = named;
  }
  throw ConfigError(*message);
}

}  // namespace granuflow
