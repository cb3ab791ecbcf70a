// Assembly of the Jacobian dF/dy + cj dF/dy': each unit's analytic part and forward AD poured through a sink (dense,
// sparse, or, for inlined explicit units, factored for the Schur complement of dae_schur.cpp).
#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "dae_internal.hpp"

namespace granuflow {

class DaeSystem::DenseSink : public JacobianSink {
 public:
  DenseSink(DaeSystem& sys, double* a, int n, int offset)
      : JacobianSink(a + offset, size_t(n)), sys_(sys), offset_(offset) {}
  void left_out(int row, int col, double value) override { sys_.record_left_out(offset_ + row, col, value); }

 private:
  DaeSystem& sys_;
  int offset_;
};

namespace {

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

// An inlined (explicit) unit's entries as a list, repeats summed later (its block over every state is mostly
// structural zeros: a sieve's 600 x 201 block holds 1200 nonzeros), and its outer products on integrated columns kept
// apart: the Schur complement applies them as rank-one updates instead of through a dense product.
class DaeSystem::FactoringSink : public JacobianSink {
 public:
  FactoringSink(DaeSystem& sys, int unit) : sys_(sys), unit_(unit), rows_(sys.zs_triplets_[unit]) {}
  void add_outer(int n_rows, const double* u, int n_cols, const int* cols, const double* w) override {
    for (int k = 0; k < n_cols; ++k)
      if (cols[k] >= sys_.n_) return JacobianSink::add_outer(n_rows, u, n_cols, cols, w);
    OuterTerm& t = next_term(sys_.outer_, sys_.n_outer_, unit_, n_rows, u);
    t.cols.assign(cols, cols + n_cols);
    t.w.assign(w, w + n_cols);
  }

 protected:
  // Straight into the unit's J_SR rows, or into the J_SS block of its read of another explicit unit (that unit's
  // columns come in runs: the owner is looked up when a run starts). Its own block is the identity of x - f.
  void add_entry(int local_row, int global_col, double value) override {
    if (value == 0.0) return;
    if (global_col < sys_.n_) {
      rows_.emplace_back(local_row, global_col, value);
      return;
    }
    if (global_col < lo_ || global_col >= hi_) {
      const auto& units = sys_.fs_.units();
      const int w = sys_.fs_.state_unit(global_col);
      lo_ = units[w].offset, hi_ = lo_ + static_cast<int>(units[w].spec.states().size());
      block_ = w == unit_ ? -1 : sys_.read_index_[size_t(unit_) * units.size() + w];
    }
    if (block_ >= 0) sys_.read_blocks_[block_].emplace_back(local_row, global_col - lo_, value);
  }

 private:
  DaeSystem& sys_;
  int unit_;
  std::vector<Eigen::Triplet<double>>& rows_;
  int lo_ = 0, hi_ = 0, block_ = -1;
};

// An integrated unit's rows in the inlined path: dense, but the part of an outer product on explicit columns is kept
// apart (rs_outer_), its part on integrated columns expanded as usual.
class DaeSystem::IntegratedSink : public JacobianSink {
 public:
  IntegratedSink(DaeSystem& sys, int unit, double* a, int ld, int offset)
      : JacobianSink(a + offset, size_t(ld)), sys_(sys), unit_(unit), offset_(offset) {}
  void left_out(int row, int col, double value) override { sys_.record_left_out(offset_ + row, col, value); }
  void add_outer(int n_rows, const double* u, int n_cols, const int* cols, const double* w) override {
    cols_.clear(), w_.clear();
    for (int k = 0; k < n_cols; ++k)
      if (cols[k] < sys_.n_) cols_.push_back(cols[k]), w_.push_back(w[k]);
    if (static_cast<int>(cols_.size()) == n_cols) return JacobianSink::add_outer(n_rows, u, n_cols, cols, w);
    if (!cols_.empty()) JacobianSink::add_outer(n_rows, u, static_cast<int>(cols_.size()), cols_.data(), w_.data());
    OuterTerm& t = next_term(sys_.rs_outer_, sys_.n_rs_outer_, unit_, n_rows, u);
    t.cols.clear(), t.w.clear();
    for (int k = 0; k < n_cols; ++k)
      if (cols[k] >= sys_.n_) t.cols.push_back(cols[k]), t.w.push_back(w[k]);
  }

 private:
  DaeSystem& sys_;
  int unit_, offset_;
  std::vector<int> cols_;
  std::vector<double> w_;
};

// The next term of `terms` (storage reused between Jacobians; the first `used` are current), for `unit` with u.
DaeSystem::OuterTerm& DaeSystem::next_term(std::vector<OuterTerm>& terms, size_t& used, int unit, int n_rows,
                                           const double* u) {
  if (used == terms.size()) terms.emplace_back();
  OuterTerm& t = terms[used++];
  t.unit = unit;
  t.u.assign(u, u + n_rows);
  return t;
}

const std::vector<std::vector<int>>& DaeSystem::conserved_blocks() const {
  if (!conserved_of_.empty() || n_ == 0) return conserved_;
  conserved_of_.assign(n_, -1);
  for (const auto& u : fs_.units()) {
    const ClassLayout& layout = u.spec.classes();
    if (u.spec.is_explicit() || !layout.class_local_newton) continue;
    for (StateId b : layout.state_blocks) {
      std::vector<int> block;
      for (int i = 0; i < layout.n; ++i)
        if (u.offset + b.i + i < n_) block.push_back(u.offset + b.i + i);
      if (block.empty()) continue;
      for (int k : block) conserved_of_[k] = static_cast<int>(conserved_.size());
      conserved_.push_back(std::move(block));
    }
  }
  return conserved_;
}

void DaeSystem::record_left_out(int state, int col, double value) {
  // a block's rows and the unknowns' columns only, in a class-local evaluation
  if (state < 0 || state >= n_ || col < 0 || col >= n_ || left_out_.empty()) return;
  const int b = conserved_of_[state];
  if (b >= 0) left_out_[size_t(b) * n_ + col] += value;
}

void DaeSystem::jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse) {
  ++n_jac_;
  if (classes_local_) {
    left_out_.assign(conserved_blocks().size() * size_t(n_), 0.0);
    left_out_y_.assign(y, y + n_);
  }
  fill_params(t);
  drive_states(y, pvals_);  // for the analytic parts; the AD sweeps drive their Jets (ad_unit)
  if (!inline_) {
    drive_outputs(t, y, yp, pvals_);
    return assemble(t, y, yp, cj, n_, dense, sparse);
  }
  if (!dense) throw std::logic_error("explicit units are inlined only with dense Jacobians");
  std::copy(y, y + n_, y_ext_.begin());
  std::copy(yp, yp + n_, yp_ext_.begin());
  evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_);
  drive_outputs(t, y_ext_.data(), yp_ext_.data(), pvals_);
  jac_ext_.resize(size_t(n_) * n_ext_);  // the integrated units' rows over every column
  n_outer_ = n_rs_outer_ = 0;
  zs_triplets_.resize(fs_.units().size());
  read_blocks_.resize(explicit_reads_.size());
  assemble(t, y_ext_.data(), yp_ext_.data(), cj, n_ext_, jac_ext_.data(), nullptr, true);
  schur_complement(dense);
}

void DaeSystem::assemble(double t, const double* y, const double* yp, double cj, int dim, double* dense, double* sparse,
                         bool factor_outer) {
  const auto& units = fs_.units();
  // The inlined path (factor_outer): `dense` holds the integrated units' rows over every column (leading dimension
  // n_), cleared by the Schur pass that reads it (jacobian()), or whole when an evaluation did not get that far;
  // explicit units list their entries in zs_triplets_ and read_blocks_ (FactoringSink).
  const int ld = factor_outer ? n_ : dim;
  if (dense && factor_outer) {
    if (!ext_clean_) std::fill(dense, dense + size_t(n_) * dim, 0.0);
    ext_clean_ = false;
    for (int u : explicit_order_) zs_triplets_[u].clear();
    for (auto& b : read_blocks_) b.clear();
  } else if (dense) {
    std::fill(dense, dense + size_t(dim) * dim, 0.0);
  }
  if (sparse) {
    pattern();  // built on first use
    std::fill(sparse, sparse + pattern_.nnz(), 0.0);
  }
  const int plain = std::min(jets_plain_, dim);
  for (int i = 0; i < plain; ++i) xj_[i].a = y[i], xdj_[i].a = yp[i];
  for (int i = plain; i < dim; ++i) xj_[i] = Jet(y[i]), xdj_[i] = Jet(yp[i]);
  jets_plain_ = 0;  // until every sweep has restored its seeds (a unit may throw)
  params_as_jets();
  for (size_t u = 0; u < units.size(); ++u) {
    const int ns = static_cast<int>(units[u].spec.states().size());
    if (ns == 0) continue;
    auto run = [&](JacobianSink& sink) {
      if (units[u].spec.has_analytic_part())
        units[u].unit->analytic_jacobian(ctx<double>(static_cast<int>(u), t, y, yp, pvals_, rbuf_.data()), cj, sink);
      if (!units[u].spec.analytic_complete()) ad_unit(static_cast<int>(u), t, y, yp, cj, sink);
    };
    if (dense && factor_outer && units[u].spec.is_explicit()) {
      FactoringSink sink(*this, static_cast<int>(u));
      sink.set_classes_local(classes_local_);
      run(sink);
    } else if (dense && factor_outer) {
      IntegratedSink sink(*this, static_cast<int>(u), dense, ld, units[u].offset);
      sink.set_classes_local(classes_local_);
      run(sink);
    } else if (dense) {
      DenseSink sink(*this, dense, ld, units[u].offset);
      sink.set_classes_local(classes_local_);
      run(sink);
    } else {
      SparseSink sink(sparse, block_pos_[u], col_map_[u], static_cast<int>(local_cols_[u].size()), units[u].name);
      run(sink);
    }
  }
  jets_plain_ = dim;
}

void DaeSystem::reference_jacobian(double t, const double* y, const double* yp, double cj, double* dense) {
  if (inline_) throw std::logic_error("reference_jacobian: build the DaeSystem without inlining");
  fill_params(t);
  drive_states(y, pvals_);
  drive_outputs(t, y, yp, pvals_);
  const auto& units = fs_.units();
  std::fill(dense, dense + size_t(n_) * n_, 0.0);
  jets_plain_ = 0;
  for (int i = 0; i < n_; ++i) xj_[i] = Jet(y[i]), xdj_[i] = Jet(yp[i]);
  params_as_jets();
  for (size_t u = 0; u < units.size(); ++u) {
    if (units[u].spec.states().empty()) continue;
    AdPlan plain;
    const bool expl = units[u].spec.is_explicit();
    const int off = units[u].offset, ns = static_cast<int>(units[u].spec.states().size());
    for (size_t j = 0; j < local_cols_[u].size(); ++j)
      if (!(expl && local_cols_[u][j] >= off && local_cols_[u][j] < off + ns))
        plain.dirs.push_back({AdPlan::kCol, static_cast<int>(j)});
    plain.row_class.assign(ns, -1);
    DenseSink sink(*this, dense, n_, off);
    ad_unit(static_cast<int>(u), t, y, yp, cj, sink, &plain);
  }
}

}  // namespace granuflow
