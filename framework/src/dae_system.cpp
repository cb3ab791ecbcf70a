#include "granuflow/dae_system.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

#include "granuflow/errors.hpp"

namespace granuflow {

DaeSystem::DaeSystem(Flowsheet& fs) : fs_(fs) {
  if (!fs_.finalized()) fs_.finalize();
  n_ = fs_.n_states();
  const auto& units = fs_.units();
  pvals_.resize(units.size());
  local_cols_.resize(units.size());
  // Columns each unit's rows can depend on: own states and every field its ports read.
  std::vector<std::set<int>> col_rows(n_);
  for (size_t u = 0; u < units.size(); ++u) {
    std::set<int> cols;
    const int ns = static_cast<int>(units[u].spec.states().size());
    for (int k = 0; k < ns; ++k) cols.insert(units[u].offset + k);
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0) cols.insert(c);
    local_cols_[u].assign(cols.begin(), cols.end());
    for (int c : cols)
      for (int k = 0; k < ns; ++k) col_rows[c].insert(units[u].offset + k);
  }
  pattern_.n = n_;
  pattern_.col_ptr.assign(n_ + 1, 0);
  for (int c = 0; c < n_; ++c) {
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
        block_pos_[u][size_t(k) * cols.size() + j] = static_cast<int>(std::lower_bound(begin, end, row) - pattern_.row_idx.begin());
      }
    }
  }
  col_map_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u)
    for (size_t j = 0; j < local_cols_[u].size(); ++j) col_map_[u][local_cols_[u][j]] = static_cast<int>(j);
  xj_.resize(n_);
  xdj_.resize(n_);
  rbuf_.resize(n_);
  reconfigure();
}

void DaeSystem::reconfigure() {
  fs_.apply_links();
  auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) {
    pvals_[u] = units[u].params;
    units[u].unit->configure(units[u].spec, units[u].params.data());
  }
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
  for (size_t u = 0; u < units.size(); ++u) {
    Ctx<double> c{t, y, yp, pvals_[u].data(), r + units[u].offset, units[u].offset, &units[u].port_index, segment_start_};
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
  DenseSink(double* a, int n, int offset) : a_(a), n_(n), offset_(offset) {}
  void add(int local_row, int global_col, double v) override { a_[size_t(global_col) * n_ + offset_ + local_row] += v; }

 private:
  double* a_;
  int n_, offset_;
};

class SparseSink : public JacobianSink {
 public:
  SparseSink(double* vals, const std::vector<int>& pos, const std::unordered_map<int, int>& col_map, int ncols,
             const std::string& unit)
      : vals_(vals), pos_(pos), col_map_(col_map), ncols_(ncols), unit_(unit) {}
  void add(int local_row, int global_col, double v) override {
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

void DaeSystem::jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse) {
  ++n_jac_;
  fill_params(t);
  const auto& units = fs_.units();
  if (dense) std::fill(dense, dense + size_t(n_) * n_, 0.0);
  if (sparse) std::fill(sparse, sparse + pattern_.nnz(), 0.0);
  for (int i = 0; i < n_; ++i) {
    xj_[i] = Jet(y[i]);
    xdj_[i] = Jet(yp[i]);
  }
  std::vector<Jet> pj;
  for (size_t u = 0; u < units.size(); ++u) {
    const int ns = static_cast<int>(units[u].spec.states().size());
    if (ns == 0) continue;
    const auto& cols = local_cols_[u];
    // Analytic Jacobian when the unit supplies one.
    Ctx<double> cd{t, y, yp, pvals_[u].data(), rbuf_.data(), units[u].offset, &units[u].port_index, segment_start_};
    bool partial = false;
    if (dense) {
      DenseSink sink(dense, n_, units[u].offset);
      if (units[u].unit->jacobian(cd, cj, sink)) continue;
      partial = units[u].unit->jacobian_part(cd, cj, sink);
    } else {
      SparseSink sink(sparse, block_pos_[u], col_map_[u], static_cast<int>(cols.size()), units[u].name);
      if (units[u].unit->jacobian(cd, cj, sink)) continue;
      partial = units[u].unit->jacobian_part(cd, cj, sink);
    }
    params_as(static_cast<int>(u), pj);
    rj_.assign(ns, Jet(0.0));
    for (size_t c0 = 0; c0 < cols.size(); c0 += kAdChunk) {
      const size_t c1 = std::min(cols.size(), c0 + kAdChunk);
      // Seed column j as direction: d/de F(y + e_j, y' + cj e_j) is column j of dF/dy + cj dF/dy'.
      for (size_t j = c0; j < c1; ++j) {
        xj_[cols[j]].v[j - c0] = 1.0;
        xdj_[cols[j]].v[j - c0] = cj;
      }
      Ctx<Jet> c{t, xj_.data(), xdj_.data(), pj.data(), rj_.data(), units[u].offset, &units[u].port_index, segment_start_,
                 partial};
      units[u].unit->residual(c);
      for (size_t j = c0; j < c1; ++j) {
        xj_[cols[j]].v[j - c0] = 0.0;
        xdj_[cols[j]].v[j - c0] = 0.0;
        for (int k = 0; k < ns; ++k) {
          const double d = rj_[k].v[j - c0];
          if (dense)
            dense[size_t(cols[j]) * n_ + units[u].offset + k] += d;
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

Status DaeSystem::sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                                const double* const* yS, const double* const* ypS, double* const* rS) {
  fill_params(t);
  const auto& units = fs_.units();
  std::vector<Jet> pj;
  rj_.assign(n_, Jet(0.0));
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    for (int i = 0; i < n_; ++i) {
      xj_[i] = Jet(y[i]);
      xdj_[i] = Jet(yp[i]);
      for (size_t d = d0; d < d1; ++d) {
        xj_[i].v[d - d0] = yS[d][i];
        xdj_[i].v[d - d0] = ypS[d][i];
      }
    }
    for (size_t u = 0; u < units.size(); ++u) {
      params_as(static_cast<int>(u), pj);
      for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj);
      Ctx<Jet> c{t, xj_.data(), xdj_.data(), pj.data(), rj_.data() + units[u].offset, units[u].offset,
                 &units[u].port_index, segment_start_};
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

void DaeSystem::initial_values(std::vector<double>& y0) const {
  y0.assign(n_, 0.0);
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) {
    InitCtx<double> c{pvals_[u].data(), y0.data() + units[u].offset};
    units[u].unit->initial(c);
  }
}

void DaeSystem::initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const {
  yS0.assign(params.size(), std::vector<double>(n_, 0.0));
  const auto& units = fs_.units();
  std::vector<Jet> pj, x0(n_);
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
