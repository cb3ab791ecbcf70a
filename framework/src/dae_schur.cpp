// Elimination of inlined explicit states from the Jacobian: the Schur complement J_RR - J_RS J_SS^-1 J_SR, its
// structure fixed at construction and its sparse row products.
#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>

#include "dae_internal.hpp"

namespace granuflow {

// Structure of the Schur complement: rows of integrated units that read explicit states, and integrated
// columns that explicit units read (Z = J_SS^-1 J_SR is zero elsewhere, explicit-to-explicit reads included).
void DaeSystem::build_schur_structure() {
  const auto& units = fs_.units();
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
  schur_pos_of_row_.assign(n_, -1);
  for (size_t pos = 0; pos < schur_rows_.size(); ++pos) schur_pos_of_row_[schur_rows_[pos]] = static_cast<int>(pos);
  const size_t nu = units.size();
  read_index_.assign(nu * nu, -1);
  for (size_t k = 0; k < explicit_reads_.size(); ++k)
    read_index_[size_t(explicit_reads_[k].first) * nu + explicit_reads_[k].second] = static_cast<int>(k);
}

void DaeSystem::SparseRows::assign(int n_rows, const std::vector<Eigen::Triplet<double>>& entries) {
  start.assign(size_t(n_rows) + 1, 0);
  for (const auto& e : entries) ++start[e.row() + 1];
  for (int r = 0; r < n_rows; ++r) start[r + 1] += start[r];
  col.resize(entries.size());
  val.resize(entries.size());
  next.assign(start.begin(), start.end() - 1);
  for (const auto& e : entries) {
    const int k = next[e.row()]++;
    col[k] = e.col(), val[k] = e.value();
  }
}

// z <- z - s zv row by row (Gustavson): a dense accumulator over the integrated columns, marked per row, so a
// product costs its multiplications and the rows it touches, whatever the blocks' area.
void DaeSystem::subtract_product(SparseRows& z, const SparseRows& s, const SparseRows& zv) {
  SparseRows& out = product_rows_;
  out.start.assign(1, 0);
  out.col.clear();
  out.val.clear();
  for (int r = 0; r < z.rows(); ++r) {
    const int stamp = ++schur_stamp_;
    const size_t first = out.col.size();
    accumulate_row(z, r, 1.0, stamp, out.col);
    for (int k = s.start[r]; k < s.start[r + 1]; ++k) accumulate_row(zv, s.col[k], -s.val[k], stamp, out.col);
    for (size_t k = first; k < out.col.size(); ++k) out.val.push_back(schur_acc_[out.col[k]]);
    out.start.push_back(static_cast<int>(out.col.size()));
  }
  std::swap(z, out);
}

void DaeSystem::accumulate_row(const SparseRows& z, int r, double a, int stamp, std::vector<int>& touched) {
  for (int q = z.start[r]; q < z.start[r + 1]; ++q) {
    const int c = z.col[q];
    if (schur_mark_[c] != stamp) schur_mark_[c] = stamp, schur_acc_[c] = 0.0, touched.push_back(c);
    schur_acc_[c] += a * z.val[q];
  }
}

// Chain rule through the explicit states: dF_R/dy_R = J_RR - J_RS J_SS^-1 J_SR, with J_SR = D + sum u_k w_k^T
// (D sparse in practice: each explicit state reads few integrated ones, apart from the outer products).
void DaeSystem::schur_complement(double* dense) {
  double* const base = jac_ext_.data();
  std::copy(base, base + size_t(n_) * n_, dense);  // J_RR
  std::fill(base, base + size_t(n_) * n_, 0.0);
  schur_rs();
  ext_clean_ = true;  // J_RR moved out, J_RS cleared as it was read
  schur_z();
  // Only rows of units that read explicit states and columns that explicit units read can change:
  // dF_R/dy_R = J_RR - J_RS Z - (J_RS U) W^T, each entry of J_RS times its row of Z added into the result.
  const int nr = static_cast<int>(schur_rows_.size()), nc = static_cast<int>(schur_cols_.size());
  if (nr == 0 || nc == 0) return;
  schur_subtract_z(dense);
  schur_subtract_rs_outer(dense);
  if (n_outer_ > 0) schur_subtract_outer(dense);
}

// J_RS on the rows that read explicit states (whole units, in order), scanned over the columns they read: these
// blocks are dense in practice (a bed's aggregation reads every class's wetted fraction), so a scan costs no more
// than listing their entries would. Each entry is cleared once read.
void DaeSystem::schur_rs() {
  const auto& units = fs_.units();
  double* const base = jac_ext_.data();
  schur_t_.clear();
  for (int pos = 0, nr = static_cast<int>(schur_rows_.size()); pos < nr;) {
    const int row = schur_rows_[pos], u = fs_.state_unit(row), len = static_cast<int>(units[u].spec.states().size());
    const auto& cols = local_cols_[u];
    for (auto it = std::lower_bound(cols.begin(), cols.end(), n_); it != cols.end(); ++it) {
      double* col = base + size_t(*it) * n_ + row;
      for (int r = 0; r < len; ++r)
        if (col[r] != 0.0) schur_t_.emplace_back(pos + r, *it - n_, col[r]), col[r] = 0.0;
    }
    pos += len;
  }
}

// Z = J_SS^-1 J_SR, one sparse block of rows per explicit unit. J_SS = I + (blocks where an explicit unit reads
// another), block unit-lower-triangular in dependency order: forward substitution over the explicit units. Both
// the blocks and Z are sparse (a screen reads its feed class by class, a mill couples every class with the coarser
// ones), so the products cost their nonzeros, not the blocks' area; explicit_reads_ lists every read of a unit
// after all reads of the units it reads, so Z_v is final when Z_u uses it.
void DaeSystem::schur_z() {
  const auto& units = fs_.units();
  const int m = n_ext_ - n_;
  const int n_terms = static_cast<int>(n_outer_);
  z_rows_.resize(units.size());
  // The explicit units' rows as their sinks sorted them: each unit's J_SR rows and the J_SS block of each read
  // between explicit units (an entry listed twice is summed by the products below, which are linear in each entry).
  for (int u : explicit_order_) z_rows_[u].assign(static_cast<int>(units[u].spec.states().size()), zs_triplets_[u]);
  Eigen::MatrixXd& zu = schur_u_;
  zu.setZero(m, n_terms);
  for (int k = 0; k < n_terms; ++k) {
    const OuterTerm& term = outer_[k];
    zu.col(k).segment(units[term.unit].offset - n_, static_cast<Eigen::Index>(term.u.size())) =
        Eigen::Map<const Eigen::VectorXd>(term.u.data(), static_cast<Eigen::Index>(term.u.size()));
  }
  schur_acc_.resize(n_);
  schur_mark_.resize(n_, 0);
  for (size_t k = 0; k < explicit_reads_.size(); ++k) {
    const auto [u, v] = explicit_reads_[k];
    const int ou = units[u].offset - n_, nu = static_cast<int>(units[u].spec.states().size());
    const int ov = units[v].offset - n_;
    s_rows_.assign(nu, read_blocks_[k]);
    subtract_product(z_rows_[u], s_rows_, z_rows_[v]);  // Z_u -= S_uv Z_v
    if (n_terms > 0)
      for (const auto& e : read_blocks_[k]) zu.row(ou + e.row()) -= e.value() * zu.row(ov + e.col());
  }
}

// Row-major, so that the rows of Z added in land on contiguous memory; one pass then subtracts it from the
// column-major result, each entry once (adding straight into the result's rows strode through it, ~14 % of the
// sieve-mill loop's run).
// Where J_RS is dense (a bed's aggregation reads every class's wetted fraction), the product goes column by column
// instead: each entry of Z adds a column of J_RS, a contiguous vector update, into a column-major result. Each
// result entry receives the same terms in the same order (explicit columns ascending), so both ways agree to the
// bit; the dense way is taken when its work is below kDenseGain times the entries the sparse way visits.
void DaeSystem::schur_subtract_z(double* dense) {
  const int m = n_ext_ - n_;
  Eigen::Map<Eigen::MatrixXd> out(dense, n_, n_);
  const auto& units = fs_.units();
  const int nr = static_cast<int>(schur_rows_.size());
  constexpr double kDenseGain = 4.0;
  // Each explicit column's row of Z, looked up once per column: J_RS lists tens of thousands of entries at 80
  // classes, and finding each one's unit through the flowsheet was most of this function's time.
  schur_zrow_.resize(size_t(m));
  for (int col = 0; col < m; ++col) {
    const int s = n_ + col, u = fs_.state_unit(s);
    schur_zrow_[col] = {&z_rows_[u], s - units[u].offset};
  }
  auto z_count = [&](int col) {
    const auto& [z, r] = schur_zrow_[col];
    return z->start[r + 1] - z->start[r];
  };
  double sparse_work = 0.0, dense_work = 0.0;
  schur_seen_.assign(size_t(m), 0);
  for (const auto& e : schur_t_) {
    const int nz = z_count(e.col());
    sparse_work += nz;
    if (!schur_seen_[e.col()]) schur_seen_[e.col()] = 1, dense_work += double(nz) * nr;
  }
  if (dense_work < kDenseGain * sparse_work) {
    schur_jd_.setZero(nr, m);
    for (const auto& e : schur_t_) schur_jd_(e.row(), e.col()) = e.value();  // each (row, column) listed once
    schur_cd_.setZero(nr, n_);
    for (int col = 0; col < m; ++col) {
      if (!schur_seen_[col]) continue;
      const auto& [z, r] = schur_zrow_[col];
      for (int q = z->start[r]; q < z->start[r + 1]; ++q) schur_cd_.col(z->col[q]) += z->val[q] * schur_jd_.col(col);
    }
    for (const auto& [pos, row, len] : schur_row_runs_) out.middleRows(row, len) -= schur_cd_.middleRows(pos, len);
  } else {
    schur_c_.setZero(nr, n_);
    for (const auto& e : schur_t_) {
      const auto& [z, r] = schur_zrow_[e.col()];
      double* row = schur_c_.data() + size_t(e.row()) * n_;
      const double a = e.value();
      for (int q = z->start[r]; q < z->start[r + 1]; ++q) row[z->col[q]] += a * z->val[q];
    }
    for (const auto& [pos, row, len] : schur_row_runs_) out.middleRows(row, len) -= schur_c_.middleRows(pos, len);
  }
}

// The factored outer products u w^T of J_RS: u (w^T Z), w^T Z accumulated over the rows of Z it weights.
void DaeSystem::schur_subtract_rs_outer(double* dense) {
  Eigen::Map<Eigen::MatrixXd> out(dense, n_, n_);
  const auto& units = fs_.units();
  for (size_t k = 0; k < n_rs_outer_; ++k) {
    const OuterTerm& term = rs_outer_[k];
    const int stamp = ++schur_stamp_;
    schur_cols_touched_.clear();
    for (size_t c = 0; c < term.cols.size(); ++c) {
      const int s = term.cols[c], u = fs_.state_unit(s);
      accumulate_row(z_rows_[u], s - units[u].offset, term.w[c], stamp, schur_cols_touched_);
    }
    const Eigen::Map<const Eigen::VectorXd> uv(term.u.data(), static_cast<Eigen::Index>(term.u.size()));
    const int row0 = units[term.unit].offset;
    for (int j : schur_cols_touched_) out.col(j).segment(row0, uv.size()).noalias() -= schur_acc_[j] * uv;
  }
}

// The explicit units' outer products u_k w_k^T of J_SR, carried through the forward substitution as the columns of
// Z_U = J_SS^-1 U (schur_u_): (J_RS Z_U) W^T, the factored outer products u w^T of J_RS entering J_RS Z_U as
// u (w^T Z_U).
void DaeSystem::schur_subtract_outer(double* dense) {
  Eigen::Map<Eigen::MatrixXd> out(dense, n_, n_);
  const auto& units = fs_.units();
  const int nr = static_cast<int>(schur_rows_.size()), nc = static_cast<int>(schur_cols_.size());
  const int n_terms = static_cast<int>(n_outer_);
  const Eigen::MatrixXd& zu = schur_u_;
  schur_p_.setZero(nr, nc);
  schur_au_.setZero(nr, n_terms);
  for (const auto& e : schur_t_) schur_au_.row(e.row()) += e.value() * zu.row(e.col());
  for (size_t k = 0; k < n_rs_outer_; ++k) {
    const OuterTerm& term = rs_outer_[k];
    Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(n_terms);
    for (size_t c = 0; c < term.cols.size(); ++c) g += term.w[c] * zu.row(term.cols[c] - n_);
    const int pos0 = schur_pos_of_row_[units[term.unit].offset];
    for (size_t i = 0; i < term.u.size(); ++i) schur_au_.row(pos0 + static_cast<int>(i)) += term.u[i] * g;
  }
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
  for (int j = 0; j < nc; ++j)
    for (const auto& [pos, row, len] : schur_row_runs_)
      out.col(schur_cols_[j]).segment(row, len) -= schur_p_.col(j).segment(pos, len);
}

}  // namespace granuflow
