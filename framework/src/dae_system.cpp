#include "granuflow/dae_system.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

#include "granuflow/errors.hpp"

namespace granuflow {

DaeSystem::DaeSystem(Flowsheet& fs, bool inline_explicit) : fs_(fs) {
  if (!fs_.finalized()) fs_.finalize();
  n_ext_ = fs_.n_states();
  inline_ = inline_explicit && fs_.n_explicit_states() > 0;
  n_ = inline_ ? n_ext_ - fs_.n_explicit_states() : n_ext_;
  const auto& units = fs_.units();
  // Explicit units in dependency order (one reading another's states comes after it).
  std::vector<std::set<int>> reads(units.size());  // per explicit unit: the other explicit units it reads
  std::vector<int> pending;
  for (size_t u = 0; u < units.size(); ++u) {
    if (!units[u].spec.is_explicit()) continue;
    pending.push_back(int(u));
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0 && units[fs_.state_unit(c)].spec.is_explicit() && fs_.state_unit(c) != int(u))
          reads[u].insert(fs_.state_unit(c));
  }
  auto ordered = [&](int v) {
    return std::find(explicit_order_.begin(), explicit_order_.end(), v) != explicit_order_.end();
  };
  while (!pending.empty()) {
    const auto next = std::find_if(pending.begin(), pending.end(),
                                   [&](int u) { return std::all_of(reads[u].begin(), reads[u].end(), ordered); });
    if (next == pending.end())
      throw ConfigError("explicit units read each other in a loop (" + units[pending.front()].name +
                        " ...): give one of them states");
    // the Schur complement's forward substitution runs over these reads
    for (int v : reads[*next]) explicit_reads_.push_back({*next, v});
    explicit_order_.push_back(*next);
    pending.erase(next);
  }
  const int n_all = n_ext_;
  pvals_.resize(units.size());
  local_cols_.resize(units.size());
  // Columns each unit's rows can depend on: own states and every field its ports read.
  for (size_t u = 0; u < units.size(); ++u) {
    std::vector<int>& cols = local_cols_[u];
    const int ns = static_cast<int>(units[u].spec.states().size());
    for (int k = 0; k < ns; ++k) cols.push_back(units[u].offset + k);
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0) cols.push_back(c);
    std::sort(cols.begin(), cols.end());
    cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    fill_ += double(ns) * double(cols.size());  // units' row blocks are disjoint
  }
  fill_ /= std::max(1.0, double(n_all) * double(n_all));
  // Structure of the Schur complement: rows of integrated units that read explicit states, and integrated
  // columns that explicit units read (Z = J_SS^-1 J_SR is zero elsewhere, explicit-to-explicit reads included).
  if (inline_) {
    std::vector<char> col_read(n_, 0);
    for (size_t u = 0; u < units.size(); ++u) {
      const auto& cols = local_cols_[u];
      if (units[u].spec.is_explicit()) {
        for (int c : cols)
          if (c < n_) col_read[c] = 1;
      } else if (!cols.empty() && cols.back() >= n_) {  // sorted: reads an explicit state
        const int off = units[u].offset, ns = static_cast<int>(units[u].spec.states().size());
        for (int k = 0; k < ns; ++k) schur_rows_.push_back(off + k);
      }
    }
    for (int c = 0; c < n_; ++c)
      if (col_read[c]) schur_cols_.push_back(c);
    for (int i = 0; i < static_cast<int>(schur_rows_.size()); ++i)  // runs of consecutive rows, copied as blocks
      if (i > 0 && schur_rows_[i] == schur_rows_[i - 1] + 1)
        ++std::get<2>(schur_row_runs_.back());
      else
        schur_row_runs_.push_back({i, schur_rows_[i], 1});
    schur_col_pos_.assign(n_, -1);
    for (size_t j = 0; j < schur_cols_.size(); ++j) schur_col_pos_[schur_cols_[j]] = static_cast<int>(j);
  }
  // Columns differentiated by AD: all local columns, except an explicit unit's own (the identity).
  ad_pos_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u) {
    const int off = units[u].offset, ns = static_cast<int>(units[u].spec.states().size());
    for (size_t j = 0; j < local_cols_[u].size(); ++j) {
      const int c = local_cols_[u][j];
      if (!(units[u].spec.is_explicit() && c >= off && c < off + ns)) ad_pos_[u].push_back(j);
    }
  }
  pj_.resize(units.size());
  xj_.resize(n_all);
  xdj_.resize(n_all);
  rbuf_.resize(n_all);
  y_ext_.resize(n_all);
  yp_ext_.resize(n_all);
  reconfigure();
  // An explicit unit's residual must be exactly x - f with f independent of x: check the slope once.
  if (inline_) {
    std::vector<double> yp0(n_ext_, 0.0), r0(n_ext_), r1(n_ext_);
    for (size_t u = 0; u < units.size(); ++u) {
      InitCtx<double> c{pvals_[u].data(), y_ext_.data() + units[u].offset};
      units[u].unit->initial(c);
    }
    for (int u : explicit_order_) {
      const int ns = static_cast<int>(units[u].spec.states().size()), off = units[u].offset;
      for (double shift : {0.0, 1.0}) {
        auto y = y_ext_;
        for (int k = 0; k < ns; ++k) y[off + k] = shift;
        Ctx<double> c{
            0.0, y.data(), yp0.data(), pvals_[u].data(), (shift > 0 ? r1 : r0).data(), off, &units[u].port_index, 0.0};
        units[u].unit->residual(c);
      }
      for (int k = 0; k < ns; ++k)
        if (std::abs(r1[k] - r0[k] - 1.0) > 1e-9)
          throw std::logic_error("unit '" + units[u].name + "' is declared explicit but the residual of state '" +
                                 units[u].spec.states()[k].name + "' is not x - f(inputs)");
    }
  }
}

// The sparsity pattern and where each unit's entries go in its values: only sparse Jacobians need them, and
// they cost a sort per column and a binary search per entry of every unit's block, so they are built on first use.
void DaeSystem::build_sparse_maps() const {
  const auto& units = fs_.units();
  const int n_all = n_ext_;
  std::vector<std::vector<int>> col_rows(n_all);
  for (size_t u = 0; u < units.size(); ++u)
    for (int c : local_cols_[u])
      for (int k = 0; k < static_cast<int>(units[u].spec.states().size()); ++k)
        col_rows[c].push_back(units[u].offset + k);
  pattern_.n = n_all;
  pattern_.col_ptr.assign(n_all + 1, 0);
  for (int c = 0; c < n_all; ++c) {
    std::sort(col_rows[c].begin(), col_rows[c].end());  // units' row blocks are disjoint: no duplicates
    pattern_.row_idx.insert(pattern_.row_idx.end(), col_rows[c].begin(), col_rows[c].end());
    pattern_.col_ptr[c + 1] = static_cast<int>(pattern_.row_idx.size());
  }
  block_pos_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u) {
    const int ns = static_cast<int>(units[u].spec.states().size());
    const auto& cols = local_cols_[u];
    block_pos_[u].assign(size_t(ns) * cols.size(), -1);
    for (size_t j = 0; j < cols.size(); ++j) {
      const int c = cols[j];
      for (int k = 0; k < ns; ++k) {
        const int row = units[u].offset + k;
        auto begin = pattern_.row_idx.begin() + pattern_.col_ptr[c];
        auto end = pattern_.row_idx.begin() + pattern_.col_ptr[c + 1];
        block_pos_[u][size_t(k) * cols.size() + j] =
            static_cast<int>(std::lower_bound(begin, end, row) - pattern_.row_idx.begin());
      }
    }
  }
  col_map_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u)
    for (size_t j = 0; j < local_cols_[u].size(); ++j) col_map_[u][local_cols_[u][j]] = static_cast<int>(j);
}

// Evaluates the explicit units in order: with their states set to zero, residual = -f.
template <class T>
void DaeSystem::evaluate_explicit(double t, T* x, T* xd, const std::vector<std::vector<T>>& params,
                                  std::vector<T>& scratch) {
  const auto& units = fs_.units();
  for (int u : explicit_order_) {
    const int ns = static_cast<int>(units[u].spec.states().size()), off = units[u].offset;
    for (int k = 0; k < ns; ++k) x[off + k] = T(0.0), xd[off + k] = T(0.0);
    scratch.resize(ns);
    Ctx<T> c{t, x, xd, params[u].data(), scratch.data(), off, &units[u].port_index, segment_start_};
    units[u].unit->residual(c);
    for (int k = 0; k < ns; ++k) x[off + k] = -scratch[k];
  }
}

void DaeSystem::extend(double t, const double* y, const double* yp, double* y_full, double* yp_full) {
  std::copy(y, y + n_, y_full);
  std::copy(yp, yp + n_, yp_full);
  if (!inline_) return;
  fill_params(t);
  evaluate_explicit(t, y_full, yp_full, pvals_, scratch_);
}

void DaeSystem::reconfigure() {
  fs_.configure_units();
  auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) pvals_[u] = units[u].params;
  fill_params(0.0);
}

void DaeSystem::fill_params(double t) {
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u)
    for (size_t k = 0; k < units[u].inputs.size(); ++k) {
      const auto& in = units[u].inputs[k];
      if (!in) continue;
      const bool step = in->interp() == PiecewiseLinear::Interp::kStep;
      pvals_[u][k] = (*in)(step ? segment_start_ : t);
    }
}

template <class T>
void DaeSystem::params_as(int unit, std::vector<T>& out) const {
  out.resize(pvals_[unit].size());
  for (size_t k = 0; k < out.size(); ++k) out[k] = T(pvals_[unit][k]);
}

Status DaeSystem::residual(double t, const double* y, const double* yp, double* r) {
  ++n_res_;
  fill_params(t);
  const auto& units = fs_.units();
  if (inline_) {
    std::copy(y, y + n_, y_ext_.begin());
    std::copy(yp, yp + n_, yp_ext_.begin());
    evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_);  // no allocation per residual
    y = y_ext_.data();
    yp = yp_ext_.data();
  }
  for (size_t u = 0; u < units.size(); ++u) {
    if (inline_ && units[u].spec.is_explicit()) continue;
    Ctx<double> c{
        t, y, yp, pvals_[u].data(), r + units[u].offset, units[u].offset, &units[u].port_index, segment_start_};
    const Status s = units[u].unit->residual(c);
    if (s != Status::kOk) return s;
  }
  for (int i = 0; i < n_; ++i)
    if (!std::isfinite(r[i])) return Status::kRecoverable;  // let the integrator cut the step, never pass NaN on
  return Status::kOk;
}

namespace {
class DenseSink : public JacobianSink {
 public:
  DenseSink(double* a, int n, int offset) : JacobianSink(a + offset, size_t(n)) {}
};

class SparseSink : public JacobianSink {
 public:
  SparseSink(double* vals, const std::vector<int>& pos, const std::unordered_map<int, int>& col_map, int ncols,
             const std::string& unit)
      : vals_(vals), pos_(pos), col_map_(col_map), ncols_(ncols), unit_(unit) {}

 protected:
  void add_entry(int local_row, int global_col, double v) override {
    auto it = col_map_.find(global_col);
    if (it == col_map_.end())
      throw std::logic_error("unit '" + unit_ + "' wrote a Jacobian entry outside its declared dependencies");
    vals_[pos_[size_t(local_row) * ncols_ + it->second]] += v;
  }

 private:
  double* vals_;
  const std::vector<int>& pos_;
  const std::unordered_map<int, int>& col_map_;
  int ncols_;
  const std::string& unit_;
};
}  // namespace

// Dense, but keeps an inlined unit's outer products on integrated columns apart: the Schur complement then
// applies them as rank-one updates instead of through a dense product.
class DaeSystem::FactoringSink : public JacobianSink {
 public:
  FactoringSink(DaeSystem& sys, int unit, double* a, int n, int offset)
      : JacobianSink(a + offset, size_t(n)), sys_(sys), unit_(unit) {}
  void add_outer(int n_rows, const double* u, int n_cols, const int* cols, const double* w) override {
    for (int k = 0; k < n_cols; ++k)
      if (cols[k] >= sys_.n_) return JacobianSink::add_outer(n_rows, u, n_cols, cols, w);
    if (sys_.n_outer_ == sys_.outer_.size()) sys_.outer_.emplace_back();
    OuterTerm& t = sys_.outer_[sys_.n_outer_++];
    t.unit = unit_;
    t.u.assign(u, u + n_rows);
    t.cols.assign(cols, cols + n_cols);
    t.w.assign(w, w + n_cols);
  }

 private:
  DaeSystem& sys_;
  int unit_;
};

void DaeSystem::jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse) {
  ++n_jac_;
  fill_params(t);
  if (!inline_) return assemble(t, y, yp, cj, n_, dense, sparse);
  if (!dense) throw std::logic_error("explicit units are inlined only with dense Jacobians");
  std::copy(y, y + n_, y_ext_.begin());
  std::copy(yp, yp + n_, yp_ext_.begin());
  evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_);
  jac_ext_.resize(size_t(n_ext_) * n_ext_);
  n_outer_ = 0;
  assemble(t, y_ext_.data(), yp_ext_.data(), cj, n_ext_, jac_ext_.data(), nullptr, true);
  // Chain rule through the explicit states: dF_R/dy_R = J_RR - J_RS J_SS^-1 J_SR, with J_SR = D + sum u_k w_k^T
  // (D sparse in practice: each explicit state reads few integrated ones, apart from the outer products).
  const int m = n_ext_ - n_;
  Eigen::Map<const Eigen::MatrixXd> J(jac_ext_.data(), n_ext_, n_ext_);
  Eigen::Map<Eigen::MatrixXd> out(dense, n_, n_);
  const auto& units = fs_.units();
  const int n_terms = static_cast<int>(n_outer_);
  Eigen::MatrixXd& z = schur_z_;
  Eigen::MatrixXd& zu = schur_u_;
  z = J.bottomLeftCorner(m, n_);
  zu.setZero(m, n_terms);
  for (int k = 0; k < n_terms; ++k) {
    const OuterTerm& term = outer_[k];
    zu.col(k).segment(units[term.unit].offset - n_, static_cast<Eigen::Index>(term.u.size())) =
        Eigen::Map<const Eigen::VectorXd>(term.u.data(), static_cast<Eigen::Index>(term.u.size()));
  }
  // J_SS = I + (blocks where an explicit unit reads another), block unit-lower-triangular in dependency order:
  // Z = J_SS^-1 [D U] by forward substitution over the explicit units, each block row solved once.
  for (const auto& [u, v] : explicit_reads_) {
    const int ou = units[u].offset - n_, nu = static_cast<int>(units[u].spec.states().size());
    const int ov = units[v].offset - n_, nv = static_cast<int>(units[v].spec.states().size());
    const auto juv = J.block(n_ + ou, n_ + ov, nu, nv);
    z.middleRows(ou, nu).noalias() -= juv * z.middleRows(ov, nv);
    if (n_terms > 0) zu.middleRows(ou, nu).noalias() -= juv * zu.middleRows(ov, nv);
  }
  // Only rows of units that read explicit states and columns that explicit units read can change.
  out = J.topLeftCorner(n_, n_);
  const int nr = static_cast<int>(schur_rows_.size()), nc = static_cast<int>(schur_cols_.size());
  if (nr == 0 || nc == 0) return;
  schur_a_.resize(nr, m);
  for (const auto& [pos, row, len] : schur_row_runs_) schur_a_.middleRows(pos, len) = J.block(row, n_, len, m);
  // P = J_RS Z over Z's nonzeros, plus (J_RS U) W^T
  schur_p_.setZero(nr, nc);
  for (int j = 0; j < nc; ++j) {
    const double* zc = z.col(schur_cols_[j]).data();
    for (int k = 0; k < m; ++k)
      if (zc[k] != 0.0) schur_p_.col(j).noalias() += zc[k] * schur_a_.col(k);
  }
  if (n_terms > 0) {
    schur_au_.noalias() = schur_a_ * zu;
    for (int k = 0; k < n_terms; ++k) {
      const OuterTerm& term = outer_[k];
      for (size_t c = 0; c < term.cols.size(); ++c) {
        const int j = schur_col_pos_[term.cols[c]];
        if (j < 0)
          throw std::logic_error("unit '" + units[term.unit].name +
                                 "' added an outer product on a column it does not read");
        schur_p_.col(j).noalias() += term.w[c] * schur_au_.col(k);
      }
    }
  }
  for (int j = 0; j < nc; ++j)
    for (const auto& [pos, row, len] : schur_row_runs_)
      out.col(schur_cols_[j]).segment(row, len) -= schur_p_.col(j).segment(pos, len);
}

void DaeSystem::assemble(double t, const double* y, const double* yp, double cj, int dim, double* dense, double* sparse,
                         bool factor_outer) {
  const auto& units = fs_.units();
  if (dense) std::fill(dense, dense + size_t(dim) * dim, 0.0);
  if (sparse) {
    pattern();  // built on first use
    std::fill(sparse, sparse + pattern_.nnz(), 0.0);
  }
  for (int i = 0; i < dim; ++i) {
    xj_[i] = Jet(y[i]);
    xdj_[i] = Jet(yp[i]);
  }
  for (size_t u = 0; u < units.size(); ++u) {
    const int ns = static_cast<int>(units[u].spec.states().size());
    if (ns == 0) continue;
    const auto& cols = local_cols_[u];
    // Analytic Jacobian when the unit supplies one.
    Ctx<double> cd{t, y, yp, pvals_[u].data(), rbuf_.data(), units[u].offset, &units[u].port_index, segment_start_};
    if (dense && factor_outer && units[u].spec.is_explicit()) {
      FactoringSink sink(*this, static_cast<int>(u), dense, dim, units[u].offset);
      if (units[u].unit->jacobian(cd, cj, sink)) continue;
    } else if (dense) {
      DenseSink sink(dense, dim, units[u].offset);
      if (units[u].unit->jacobian(cd, cj, sink)) continue;
    } else {
      SparseSink sink(sparse, block_pos_[u], col_map_[u], static_cast<int>(cols.size()), units[u].name);
      if (units[u].unit->jacobian(cd, cj, sink)) continue;
    }
    std::vector<Jet>& pj = pj_[u];
    params_as(static_cast<int>(u), pj);
    rj_.assign(ns, Jet(0.0));
    // An explicit unit's residual is x - f: its own columns are the identity, no AD needed.
    const std::vector<size_t>& ad = ad_pos_[u];
    if (units[u].spec.is_explicit())
      for (int k = 0; k < ns; ++k) {
        const int col = units[u].offset + k;
        if (dense)
          dense[size_t(col) * dim + col] += 1.0;
        else
          sparse[block_pos_[u][size_t(k) * cols.size() + col_map_[u].at(col)]] += 1.0;
      }
    for (size_t a0 = 0; a0 < ad.size(); a0 += kAdChunk) {
      const size_t a1 = std::min(ad.size(), a0 + kAdChunk);
      // Seed column j as direction: d/de F(y + e_j, y' + cj e_j) is column j of dF/dy + cj dF/dy'.
      for (size_t a = a0; a < a1; ++a) {
        xj_[cols[ad[a]]].v[a - a0] = 1.0;
        xdj_[cols[ad[a]]].v[a - a0] = cj;
      }
      Ctx<Jet> c{t,          xj_.data(),      xdj_.data(),          pj.data(),
                 rj_.data(), units[u].offset, &units[u].port_index, segment_start_};
      units[u].unit->residual(c);
      for (size_t a = a0; a < a1; ++a) {
        const size_t j = ad[a];
        xj_[cols[j]].v[a - a0] = 0.0;
        xdj_[cols[j]].v[a - a0] = 0.0;
        for (int k = 0; k < ns; ++k) {
          const double d = rj_[k].v[a - a0];
          if (dense)
            dense[size_t(cols[j]) * dim + units[u].offset + k] += d;
          else
            sparse[block_pos_[u][size_t(k) * cols.size() + j]] += d;
        }
      }
    }
  }
}

// Seeds direction `slot` for parameter `id` and the parameters linked to it, where they belong to unit `u`.
void DaeSystem::seed(int id, int u, size_t slot, std::vector<Jet>& pj) const {
  auto [pu, pk] = fs_.param_location(id);
  if (pu == u) pj[pk].v[slot] = 1.0;
  for (int t : fs_.linked_targets(id)) {
    auto [tu, tk] = fs_.param_location(t);
    if (tu == u) pj[tk].v[slot] = 1.0;
  }
}

// Loads directions [d0, d1) into the Jets: the unknowns' values and sensitivities (y' ones zero without `ypS`),
// and every unit's parameters seeded with the directions of the parameters they are or follow.
void DaeSystem::load_directions(const double* y, const double* yp, const std::vector<int>& params, size_t d0, size_t d1,
                                const double* const* yS, const double* const* ypS) {
  for (int i = 0; i < n_; ++i) {
    xj_[i] = Jet(y[i]);
    xdj_[i] = Jet(yp[i]);
    for (size_t d = d0; d < d1; ++d) {
      xj_[i].v[d - d0] = yS[d][i];
      if (ypS) xdj_[i].v[d - d0] = ypS[d][i];
    }
  }
  for (size_t u = 0; u < pj_.size(); ++u) {
    params_as(static_cast<int>(u), pj_[u]);
    for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj_[u]);
  }
}

Status DaeSystem::sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                                const double* const* yS, const double* const* ypS, double* const* rS) {
  fill_params(t);
  const auto& units = fs_.units();
  rj_.assign(n_ext_, Jet(0.0));
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, ypS);
    if (inline_) evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    for (size_t u = 0; u < units.size(); ++u) {
      if (inline_ && units[u].spec.is_explicit()) continue;
      Ctx<Jet> c{t,
                 xj_.data(),
                 xdj_.data(),
                 pj_[u].data(),
                 rj_.data() + units[u].offset,
                 units[u].offset,
                 &units[u].port_index,
                 segment_start_};
      const Status s = units[u].unit->residual(c);
      if (s != Status::kOk) return s;
    }
    for (size_t d = d0; d < d1; ++d)
      for (int i = 0; i < n_; ++i) {
        rS[d][i] = rj_[i].v[d - d0];
        if (!std::isfinite(rS[d][i])) return Status::kRecoverable;
      }
  }
  return Status::kOk;
}

void DaeSystem::extend_sensitivities(double t, const double* y, const double* yp, const std::vector<int>& params,
                                     const double* const* yS, double* const* yS_full) {
  for (size_t d = 0; d < params.size(); ++d) std::copy(yS[d], yS[d] + n_, yS_full[d]);
  if (!inline_) return;
  fill_params(t);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr);
    evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    for (size_t d = d0; d < d1; ++d)
      for (int i = n_; i < n_ext_; ++i) yS_full[d][i] = xj_[i].v[d - d0];
  }
}

void DaeSystem::initial_values(std::vector<double>& y0) const {
  y0.assign(n_ext_, 0.0);
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) {
    InitCtx<double> c{pvals_[u].data(), y0.data() + units[u].offset};
    units[u].unit->initial(c);
  }
  y0.resize(n_);  // explicit states, if inlined, are computed, not integrated
}

void DaeSystem::initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const {
  yS0.assign(params.size(), std::vector<double>(n_, 0.0));
  const auto& units = fs_.units();
  std::vector<Jet> pj, x0(n_ext_);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    for (size_t u = 0; u < units.size(); ++u) {
      params_as(static_cast<int>(u), pj);
      for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj);
      InitCtx<Jet> c{pj.data(), x0.data() + units[u].offset};
      units[u].unit->initial(c);
    }
    for (size_t d = d0; d < d1; ++d)
      for (int i = 0; i < n_; ++i) yS0[d][i] = x0[i].v[d - d0];
  }
}

std::vector<double> DaeSystem::differential_id() const {
  std::vector<double> id(n_);
  for (int i = 0; i < n_; ++i) id[i] = fs_.state_spec(i).kind == StateKind::Differential ? 1.0 : 0.0;
  return id;
}

std::vector<double> DaeSystem::scales() const {
  std::vector<double> s(n_);
  for (int i = 0; i < n_; ++i) s[i] = fs_.state_spec(i).scale;
  return s;
}

void DaeSystem::report(double t, const double* y, const double* yp, double* out) {
  fill_params(t);
  const auto& units = fs_.units();
  int k = 0;
  for (size_t u = 0; u < units.size(); ++u) {
    const int no = static_cast<int>(units[u].spec.outputs().size());
    if (no == 0) continue;
    Ctx<double> c{t, y, yp, pvals_[u].data(), rbuf_.data(), units[u].offset, &units[u].port_index, segment_start_};
    units[u].unit->report(c, out + k);
    k += no;
  }
}

std::string DaeSystem::describe_row(int row) const {
  const auto& u = fs_.units()[fs_.state_unit(row)];
  return "unit '" + u.name + "' (equation of state '" + u.spec.states()[row - u.offset].name + "')";
}

}  // namespace granuflow
