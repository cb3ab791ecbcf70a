// Layout of the DAE system: explicit units' order, each unit's columns and AD plan, the sparse pattern, parameters
// and inputs, initial values and per-state metadata.
#include "granuflow/dae_system.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

#include "dae_internal.hpp"
#include "granuflow/errors.hpp"

namespace granuflow {

namespace {

// Per unit: the other explicit units whose states it reads, if it is explicit itself.
std::vector<std::set<int>> explicit_reads_of(const Flowsheet& fs) {
  const auto& units = fs.units();
  std::vector<std::set<int>> reads(units.size());
  for (size_t u = 0; u < units.size(); ++u) {
    if (!units[u].spec.is_explicit()) continue;
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0 && units[fs.state_unit(c)].spec.is_explicit() && fs.state_unit(c) != int(u))
          reads[u].insert(fs.state_unit(c));
  }
  return reads;
}

// Explicit units in dependency order (one reading another's states comes after it), and their reads (u, v) in that
// order.
void order_explicit(const Flowsheet& fs, const std::vector<std::set<int>>& reads, std::vector<int>& order,
                    std::vector<std::pair<int, int>>& explicit_reads) {
  const auto& units = fs.units();
  std::vector<int> pending;
  for (size_t u = 0; u < units.size(); ++u)
    if (units[u].spec.is_explicit()) pending.push_back(int(u));
  auto ordered = [&](int v) { return std::find(order.begin(), order.end(), v) != order.end(); };
  while (!pending.empty()) {
    const auto next = std::find_if(pending.begin(), pending.end(),
                                   [&](int u) { return std::all_of(reads[u].begin(), reads[u].end(), ordered); });
    if (next == pending.end())
      throw ConfigError("explicit units read each other in a loop (" + units[pending.front()].name +
                        " ...): give one of them states");
    // the Schur complement's forward substitution runs over these reads
    for (int v : reads[*next]) explicit_reads.push_back({*next, v});
    order.push_back(*next);
    pending.erase(next);
  }
}

// The explicit units the quadrature rates need: those whose states a unit with quadratures reads, and the
// explicit units these read in turn. A quadrature evaluation (once per integrator step) skips the others.
std::vector<int> quadrature_explicit(const Flowsheet& fs, const std::vector<std::set<int>>& reads,
                                     const std::vector<int>& order) {
  const auto& units = fs.units();
  std::vector<int> quad_explicit;
  std::vector<char> need(units.size(), 0);
  auto mark = [&](int u) {
    if (units[u].spec.is_explicit()) need[u] = 1;
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0 && units[fs.state_unit(c)].spec.is_explicit()) need[fs.state_unit(c)] = 1;
  };
  for (size_t u = 0; u < units.size(); ++u)
    if (!units[u].spec.quadratures().empty()) mark(static_cast<int>(u));
  for (auto it = order.rbegin(); it != order.rend(); ++it)  // readers before what they read
    if (need[*it])
      for (int v : reads[*it]) need[v] = 1;
  for (int u : order)
    if (need[u]) quad_explicit.push_back(u);
  return quad_explicit;
}

}  // namespace

DaeSystem::~DaeSystem() = default;

DaeSystem::DaeSystem(const Flowsheet& fs, bool inline_explicit) : fs_(fs) {
  if (!fs_.finalized()) throw std::logic_error("DaeSystem: finalize the flowsheet first");
  n_ext_ = fs_.n_states();
  n_quad_ = fs_.n_quadratures();
  inline_ = inline_explicit && fs_.n_explicit_states() > 0;
  n_ = inline_ ? n_ext_ - fs_.n_explicit_states() : n_ext_;
  const auto& units = fs_.units();
  const std::vector<std::set<int>> reads = explicit_reads_of(fs_);
  order_explicit(fs_, reads, explicit_order_, explicit_reads_);
  quad_explicit_ = quadrature_explicit(fs_, reads, explicit_order_);
  const int n_all = n_ext_;
  pvals_.resize(units.size());
  pconst_.resize(units.size());
  local_cols_.resize(units.size());
  drives_ = resolve_drives(fs_);
  for (const auto& d : drives_) output_drives_ = output_drives_ || d.source_unit >= 0;
  // Columns each unit's rows can depend on: own states and every field its ports read, and what drives its
  // parameters: a state, or the columns of a measured unit (its own and its ports', and its drives' states).
  auto unit_columns = [&](int u, std::vector<int>& cols) {
    const int ns = static_cast<int>(units[u].spec.states().size());
    for (int k = 0; k < ns; ++k) cols.push_back(units[u].offset + k);
    for (const auto& port : units[u].port_index)
      for (int c : port)
        if (c >= 0) cols.push_back(c);
    for (const auto& d : drives_)
      if (d.unit == u && d.state >= 0) cols.push_back(d.state);
  };
  for (size_t u = 0; u < units.size(); ++u) {
    std::vector<int>& cols = local_cols_[u];
    const int ns = static_cast<int>(units[u].spec.states().size());
    unit_columns(static_cast<int>(u), cols);
    for (const auto& d : drives_)
      if (d.unit == int(u) && d.source_unit >= 0) unit_columns(d.source_unit, cols);
    std::sort(cols.begin(), cols.end());
    cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    fill_ += double(ns) * double(cols.size());  // units' row blocks are disjoint
  }
  fill_ /= std::max(1.0, double(n_all) * double(n_all));
  if (inline_) build_schur_structure();
  plans_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u) build_ad_plan(static_cast<int>(u));
  ws_.resize(units.size());
  for (size_t u = 0; u < units.size(); ++u) ws_[u] = units[u].unit->workspace();
  pj_.resize(units.size());
  xj_.resize(n_all);
  xdj_.resize(n_all);
  qj_.resize(n_quad_);
  rbuf_.resize(n_all);
  y_ext_.resize(n_all);
  yp_ext_.resize(n_all);
  reconfigure();
  if (inline_) check_explicit_residuals();
}

// An explicit unit's residual must be exactly x - f with f independent of x: check the slope once.
void DaeSystem::check_explicit_residuals() {
  const auto& units = fs_.units();
  std::vector<double> yp0(n_ext_, 0.0), r0(n_ext_), r1(n_ext_);
  for (size_t u = 0; u < units.size(); ++u) {
    InitCtx<double> c{pvals_[u].data(), y_ext_.data() + units[u].offset};
    if (units[u].shared >= 0) c.shared = pvals_[units[u].shared].data();
    c.work = ws_[u].get();
    units[u].unit->initial(c);
  }
  for (int u : explicit_order_) {
    const int ns = static_cast<int>(units[u].spec.states().size()), off = units[u].offset;
    for (double shift : {0.0, 1.0}) {
      auto y = y_ext_;
      for (int k = 0; k < ns; ++k) y[off + k] = shift;
      units[u].unit->residual(ctx<double>(u, 0.0, y.data(), yp0.data(), pvals_, (shift > 0 ? r1 : r0).data()));
    }
    for (int k = 0; k < ns; ++k)
      if (std::abs(r1[k] - r0[k] - 1.0) > 1e-9)
        throw std::logic_error("unit '" + units[u].name + "' is declared explicit but the residual of state '" +
                               units[u].spec.states()[k].name + "' is not x - f(inputs)");
  }
}

void DaeSystem::unit_replaced(int u) { ws_[u] = fs_.units()[u].unit->workspace(); }

void DaeSystem::reconfigure() {
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) pconst_[u] = fs_.run_params(static_cast<int>(u));
  for (size_t u = 0; u < units.size(); ++u) {
    try {
      units[u].unit->check(units[u].spec, pconst_[u].data());
      units[u].unit->configure(units[u].spec, pconst_[u].data(),
                               units[u].shared >= 0 ? pconst_[units[u].shared].data() : nullptr, *ws_[u]);
    } catch (const ConfigError& e) {
      throw ConfigError(fs_.qualify_unit_message(static_cast<int>(u), e.what()));
    }
  }
  pvals_ = pconst_;
  inputs_.clear();
  for (size_t u = 0; u < units.size(); ++u)
    for (size_t k = 0; k < units[u].inputs.size(); ++k)
      if (units[u].inputs[k]) inputs_.push_back({static_cast<int>(u), static_cast<int>(k)});
  fill_params(0.0);
}

void DaeSystem::begin_run() {
  segment_start_ = 0.0;  // before reconfigure(): step inputs are read at the segment start
  n_res_ = n_jac_ = 0;
  completed_ = false;
  reconfigure();
}

void DaeSystem::fill_params(double t) {
  const auto& units = fs_.units();
  for (const auto& [u, k] : inputs_) {
    const auto& in = units[u].inputs[k];
    const bool step = in->interp() == PiecewiseLinear::Interp::kStep;
    pvals_[u][k] = (*in)(step ? segment_start_ : t);
  }
}

void DaeSystem::params_as_jets() {
  for (size_t u = 0; u < pvals_.size(); ++u) {
    pj_[u].resize(pvals_[u].size());
    for (size_t k = 0; k < pvals_[u].size(); ++k) pj_[u][k] = Jet(pvals_[u][k]);
  }
}

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

void DaeSystem::initial_values(std::vector<double>& y0) const {
  y0.assign(n_ext_, 0.0);
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u) {
    InitCtx<double> c{pvals_[u].data(), y0.data() + units[u].offset};
    if (units[u].shared >= 0) c.shared = pvals_[units[u].shared].data();
    c.work = ws_[u].get();
    units[u].unit->initial(c);
  }
  y0.resize(n_);  // explicit states, if inlined, are computed, not integrated
}

std::vector<double> DaeSystem::differential_id() const {
  std::vector<double> id(n_);
  for (int i = 0; i < n_; ++i) id[i] = fs_.state_spec(i).kind == StateKind::Differential ? 1.0 : 0.0;
  return id;
}

std::vector<double> DaeSystem::scales() const {
  std::vector<double> s(n_ext_);
  for (int i = 0; i < n_ext_; ++i) s[i] = fs_.state_spec(i).scale;
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u)
    units[u].unit->tolerance_scales(pvals_[u].data(), units[u].shared >= 0 ? pvals_[units[u].shared].data() : nullptr,
                                    s.data() + units[u].offset);
  s.resize(n_);
  return s;
}

std::vector<double> DaeSystem::constraints() const {
  std::vector<double> c(n_, 0.0);
  bool any = false;
  for (int i = 0; i < n_; ++i)
    if (fs_.state_spec(i).nonnegative && fs_.state_spec(i).enforced) c[i] = 1.0, any = true;
  if (!any) c.clear();
  return c;
}

std::vector<double> DaeSystem::quadrature_scales() const {
  std::vector<double> s;
  for (const auto& u : fs_.units())
    for (const auto& q : u.spec.quadratures()) s.push_back(q.scale);
  return s;
}

std::string DaeSystem::describe_row(int row) const {
  const auto& u = fs_.units()[fs_.state_unit(row)];
  return "unit '" + u.name + "' (equation of state '" + u.spec.states()[row - u.offset].name + "')";
}

}  // namespace granuflow
