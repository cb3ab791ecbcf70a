#include "granuflow/dae_system.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

#include "granuflow/errors.hpp"

namespace granuflow {

// How the AD sweeps of one unit seed their directions. A direction is a class block (one column per class, all
// classes at once: class rows may only read their own class, so the columns never mix), a single shared column, or
// a reduction (the sum's derivative is cut and the reduction seeded as an independent variable; its own derivative
// is collected term by term and re-enters as an outer product).
struct DaeSystem::AdPlan {
  enum Kind { kClass, kCol, kReduction };
  struct Dir {
    Kind kind;
    int index;  // class block, position in local_cols_, or reduction
  };
  std::vector<Dir> dirs;
  std::vector<std::vector<int>> class_cols;  // [block][class] global column, -1 (open optional port)
  std::vector<std::vector<int>> class_pos;   // [block][class] position in local_cols_
  std::vector<char> class_seeded;            // explicit units' own blocks are rows only (identity columns)
  std::vector<int> row_class;                // per own state: its class, or -1 (scalar row)
  int reductions = 0;
  bool recorded = false;  // the unit needs a recorder (reductions, or an analytic part to skip)
};

// Collects the reductions' derivatives during the AD sweeps of one unit.
class DaeSystem::Recorder : public ReductionRecorder {
 public:
  Recorder(const AdPlan& plan, const std::string& unit, size_t n_cols, int n_rows)
      : plan_(plan),
        unit_(unit),
        w_(plan.reductions, std::vector<double>(n_cols, 0.0)),
        dz_(plan.reductions, std::vector<double>(plan.reductions, 0.0)),
        u_(plan.reductions, std::vector<double>(n_rows, 0.0)) {}
  void sweep(size_t d0, size_t d1) {
    d0_ = d0, d1_ = d1;
    next_ = 0;
  }
  void term(ReductionId r, int cls, const Jet& v) override {
    if (r.i < next_) order_error(r);
    next_ = r.i;
    for (size_t d = d0_; d < d1_; ++d) {
      const double val = v.v[d - d0_];
      if (val == 0.0) continue;
      const AdPlan::Dir& dir = plan_.dirs[d];
      if (dir.kind == AdPlan::kClass) {
        if (cls >= static_cast<int>(plan_.class_pos[dir.index].size()))
          throw std::logic_error("unit '" + unit_ + "': a reduction term reads a class beyond the class layout");
        if (plan_.class_cols[dir.index][cls] >= 0) w_[r.i][plan_.class_pos[dir.index][cls]] += val;
      } else if (dir.kind == AdPlan::kCol) {
        w_[r.i][dir.index] += val;
      } else if (dir.index < r.i) {
        dz_[r.i][dir.index] += val;
      } else {
        throw std::logic_error("unit '" + unit_ + "': reduction " + std::to_string(r.i) + " reads reduction " +
                               std::to_string(dir.index) + ", declared after it");
      }
    }
  }
  Jet result(ReductionId r, double value) override {
    if (r.i < next_) order_error(r);
    next_ = r.i + 1;
    Jet j(value);
    for (size_t d = d0_; d < d1_; ++d)
      if (plan_.dirs[d].kind == AdPlan::kReduction && plan_.dirs[d].index == r.i) j.v[d - d0_] = 1.0;
    return j;
  }
  double& u(int r, int row) { return u_[r][row]; }
  // The reductions' total derivatives (through earlier reductions too), added as outer products u w^T.
  void finish(const std::vector<int>& cols, JacobianSink& sink) {
    std::vector<int> c;
    std::vector<double> w;
    for (int r = 0; r < plan_.reductions; ++r) {
      for (int r2 = 0; r2 < r; ++r2)
        if (dz_[r][r2] != 0.0)
          for (size_t k = 0; k < cols.size(); ++k) w_[r][k] += dz_[r][r2] * w_[r2][k];
      c.clear(), w.clear();
      for (size_t k = 0; k < cols.size(); ++k)
        if (w_[r][k] != 0.0) c.push_back(cols[k]), w.push_back(w_[r][k]);
      if (!c.empty())
        sink.add_outer(static_cast<int>(u_[r].size()), u_[r].data(), static_cast<int>(c.size()), c.data(), w.data());
    }
  }

 private:
  [[noreturn]] void order_error(ReductionId r) const {
    throw std::logic_error("unit '" + unit_ + "': reduction " + std::to_string(r.i) +
                           " evaluated out of declaration order (or twice) in one residual");
  }
  const AdPlan& plan_;
  const std::string& unit_;
  std::vector<std::vector<double>> w_, dz_, u_;
  size_t d0_ = 0, d1_ = 0;
  int next_ = 0;
};

DaeSystem::~DaeSystem() = default;

DaeSystem::DaeSystem(const Flowsheet& fs, bool inline_explicit) : fs_(fs) {
  if (!fs_.finalized()) throw std::logic_error("DaeSystem: finalize the flowsheet first");
  n_ext_ = fs_.n_states();
  n_quad_ = fs_.n_quadratures();
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
  // The explicit units the quadrature rates need: those whose states a unit with quadratures reads, and the
  // explicit units these read in turn. A quadrature evaluation (once per integrator step) skips the others.
  {
    std::vector<char> need(units.size(), 0);
    auto mark = [&](int u) {
      if (units[u].spec.is_explicit()) need[u] = 1;
      for (const auto& port : units[u].port_index)
        for (int c : port)
          if (c >= 0 && units[fs_.state_unit(c)].spec.is_explicit()) need[fs_.state_unit(c)] = 1;
    };
    for (size_t u = 0; u < units.size(); ++u)
      if (!units[u].spec.quadratures().empty()) mark(static_cast<int>(u));
    for (auto it = explicit_order_.rbegin(); it != explicit_order_.rend(); ++it)  // readers before what they read
      if (need[*it])
        for (int v : reads[*it]) need[v] = 1;
    for (int u : explicit_order_)
      if (need[u]) quad_explicit_.push_back(u);
  }
  const int n_all = n_ext_;
  pvals_.resize(units.size());
  pconst_.resize(units.size());
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
    schur_pos_of_row_.assign(n_, -1);
    for (size_t pos = 0; pos < schur_rows_.size(); ++pos) schur_pos_of_row_[schur_rows_[pos]] = static_cast<int>(pos);
    const size_t nu = units.size();
    read_index_.assign(nu * nu, -1);
    for (size_t k = 0; k < explicit_reads_.size(); ++k)
      read_index_[size_t(explicit_reads_[k].first) * nu + explicit_reads_[k].second] = static_cast<int>(k);
  }
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
  // An explicit unit's residual must be exactly x - f with f independent of x: check the slope once.
  if (inline_) {
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
}

void DaeSystem::build_ad_plan(int u) {
  const UnitInstance& inst = fs_.units()[u];
  const UnitSpec& spec = inst.spec;
  auto plan = std::make_unique<AdPlan>();
  const auto& cols = local_cols_[u];
  const int ns = static_cast<int>(spec.states().size()), off = inst.offset;
  const bool expl = spec.is_explicit();
  auto pos_of = [&](int col) {
    return static_cast<int>(std::lower_bound(cols.begin(), cols.end(), col) - cols.begin());
  };
  std::vector<char> in_class(cols.size(), 0);
  plan->row_class.assign(ns, -1);
  const ClassLayout& cl = spec.classes();
  auto add_block = [&](std::vector<int> global, bool seeded) {
    std::vector<int> pos(global.size(), -1);
    for (size_t i = 0; i < global.size(); ++i)
      if (global[i] >= 0) pos[i] = pos_of(global[i]), in_class[pos[i]] = 1;
    plan->class_cols.push_back(std::move(global));
    plan->class_pos.push_back(std::move(pos));
    plan->class_seeded.push_back(seeded);
  };
  for (StateId b : cl.state_blocks) {
    std::vector<int> g(cl.n);
    for (int i = 0; i < cl.n; ++i) g[i] = off + b.i + i, plan->row_class[b.i + i] = i;
    add_block(std::move(g), !expl);
  }
  for (auto [port, first] : cl.field_blocks) {
    std::vector<int> g(cl.n);
    for (int i = 0; i < cl.n; ++i) g[i] = inst.port_index[port.i][first + i];
    add_block(std::move(g), true);
  }
  for (size_t b = 0; b < plan->class_cols.size(); ++b)
    if (plan->class_seeded[b]) plan->dirs.push_back({AdPlan::kClass, static_cast<int>(b)});
  for (size_t j = 0; j < cols.size(); ++j) {
    if (in_class[j]) continue;
    if (expl && cols[j] >= off && cols[j] < off + ns) continue;  // x - f: the identity, no AD needed
    plan->dirs.push_back({AdPlan::kCol, static_cast<int>(j)});
  }
  plan->reductions = static_cast<int>(spec.reductions().size());
  for (int r = 0; r < plan->reductions; ++r) plan->dirs.push_back({AdPlan::kReduction, r});
  plan->recorded = plan->reductions > 0 || spec.has_analytic_part() || cl.n > 0;
  plans_[u] = std::move(plan);
}

template <class T>
Ctx<T> DaeSystem::ctx(int u, double t, const T* y, const T* yp, const std::vector<std::vector<T>>& params, T* r) const {
  const UnitInstance& inst = fs_.units()[u];
  Ctx<T> c{t, y, yp, params[u].data(), r, inst.offset, &inst.port_index, segment_start_};
  c.work = ws_[u].get();
  c.port_runs = &inst.port_runs;
  if (inst.shared >= 0) c.shared = params[inst.shared].data();
  return c;
}

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

// Evaluates the explicit units in order: with their states set to zero, residual = -f.
template <class T>
void DaeSystem::evaluate_explicit(double t, T* x, T* xd, const std::vector<std::vector<T>>& params,
                                  std::vector<T>& scratch, const std::vector<int>* only) {
  const auto& units = fs_.units();
  // The explicit states have no derivatives: yp_ext_ holds their zeros from its construction (nothing else writes
  // them), other arrays get them here.
  bool zero_xd = true;
  if constexpr (std::is_same_v<T, double>) zero_xd = xd != yp_ext_.data();
  for (int u : only ? *only : explicit_order_) {
    const int ns = static_cast<int>(units[u].spec.states().size()), off = units[u].offset;
    std::fill(x + off, x + off + ns, T(0.0));  // x = 0: the residual x - f is then -f exactly
    if (zero_xd) std::fill(xd + off, xd + off + ns, T(0.0));
    scratch.resize(ns);
    units[u].unit->residual(ctx<T>(u, t, x, xd, params, scratch.data()));
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
    const Status s = units[u].unit->residual(ctx<double>(static_cast<int>(u), t, y, yp, pvals_, r + units[u].offset));
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
      : JacobianSink(a + offset, size_t(ld)), sys_(sys), unit_(unit) {}
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
  int unit_;
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

void DaeSystem::jacobian(double t, const double* y, const double* yp, double cj, double* dense, double* sparse) {
  ++n_jac_;
  fill_params(t);
  if (!inline_) return assemble(t, y, yp, cj, n_, dense, sparse);
  if (!dense) throw std::logic_error("explicit units are inlined only with dense Jacobians");
  std::copy(y, y + n_, y_ext_.begin());
  std::copy(yp, yp + n_, yp_ext_.begin());
  evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_);
  jac_ext_.resize(size_t(n_) * n_ext_);  // the integrated units' rows over every column
  n_outer_ = n_rs_outer_ = 0;
  zs_triplets_.resize(fs_.units().size());
  read_blocks_.resize(explicit_reads_.size());
  assemble(t, y_ext_.data(), yp_ext_.data(), cj, n_ext_, jac_ext_.data(), nullptr, true);
  // Chain rule through the explicit states: dF_R/dy_R = J_RR - J_RS J_SS^-1 J_SR, with J_SR = D + sum u_k w_k^T
  // (D sparse in practice: each explicit state reads few integrated ones, apart from the outer products).
  const int m = n_ext_ - n_;
  Eigen::Map<Eigen::MatrixXd> out(dense, n_, n_);
  const auto& units = fs_.units();
  const int n_terms = static_cast<int>(n_outer_);
  // Z = J_SS^-1 J_SR, one sparse block of rows per explicit unit. J_SS = I + (blocks where an explicit unit reads
  // another), block unit-lower-triangular in dependency order: forward substitution over the explicit units. Both
  // the blocks and Z are sparse (a screen reads its feed class by class, a mill couples every class with the coarser
  // ones), so the products cost their nonzeros, not the blocks' area; explicit_reads_ lists every read of a unit
  // after all reads of the units it reads, so Z_v is final when Z_u uses it.
  z_rows_.resize(units.size());
  double* const base = jac_ext_.data();
  std::copy(base, base + size_t(n_) * n_, dense);  // J_RR
  std::fill(base, base + size_t(n_) * n_, 0.0);
  // J_RS on the rows that read explicit states (whole units, in order), scanned over the columns they read: these
  // blocks are dense in practice (a bed's aggregation reads every class's wetted fraction), so a scan costs no more
  // than listing their entries would. Each entry is cleared once read.
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
  // The explicit units' rows as their sinks sorted them: each unit's J_SR rows and the J_SS block of each read
  // between explicit units (an entry listed twice is summed by the products below, which are linear in each entry).
  ext_clean_ = true;
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
  // Only rows of units that read explicit states and columns that explicit units read can change:
  // dF_R/dy_R = J_RR - J_RS Z - (J_RS U) W^T, each entry of J_RS times its row of Z added into the result.
  const int nr = static_cast<int>(schur_rows_.size()), nc = static_cast<int>(schur_cols_.size());
  if (nr == 0 || nc == 0) return;
  // Row-major, so that the rows of Z added in land on contiguous memory; one pass then subtracts it from the
  // column-major result, each entry once (adding straight into the result's rows strode through it, ~14 % of the
  // sieve-mill loop's run).
  // Where J_RS is dense (a bed's aggregation reads every class's wetted fraction), the product goes column by column
  // instead: each entry of Z adds a column of J_RS, a contiguous vector update, into a column-major result. Each
  // result entry receives the same terms in the same order (explicit columns ascending), so both ways agree to the
  // bit; the dense way is taken when its work is below kDenseGain times the entries the sparse way visits.
  constexpr double kDenseGain = 4.0;
  auto z_count = [&](int col) {
    const int s = n_ + col, u = fs_.state_unit(s), r = s - units[u].offset;
    return z_rows_[u].start[r + 1] - z_rows_[u].start[r];
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
      const int s = n_ + col, u = fs_.state_unit(s), r = s - units[u].offset;
      const SparseRows& z = z_rows_[u];
      for (int q = z.start[r]; q < z.start[r + 1]; ++q) schur_cd_.col(z.col[q]) += z.val[q] * schur_jd_.col(col);
    }
    for (const auto& [pos, row, len] : schur_row_runs_) out.middleRows(row, len) -= schur_cd_.middleRows(pos, len);
  } else {
    schur_c_.setZero(nr, n_);
    for (const auto& e : schur_t_) {
      const int s = n_ + e.col(), u = fs_.state_unit(s), r = s - units[u].offset;
      const SparseRows& z = z_rows_[u];
      double* row = schur_c_.data() + size_t(e.row()) * n_;
      const double a = e.value();
      for (int q = z.start[r]; q < z.start[r + 1]; ++q) row[z.col[q]] += a * z.val[q];
    }
    for (const auto& [pos, row, len] : schur_row_runs_) out.middleRows(row, len) -= schur_c_.middleRows(pos, len);
  }
  // The factored outer products u w^T of J_RS: u (w^T Z), w^T Z accumulated over the rows of Z it weights.
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
  if (n_terms > 0) {
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
      run(sink);
    } else if (dense && factor_outer) {
      IntegratedSink sink(*this, static_cast<int>(u), dense, ld, units[u].offset);
      run(sink);
    } else if (dense) {
      DenseSink sink(dense, ld, units[u].offset);
      run(sink);
    } else {
      SparseSink sink(sparse, block_pos_[u], col_map_[u], static_cast<int>(local_cols_[u].size()), units[u].name);
      run(sink);
    }
  }
  jets_plain_ = dim;
}

// Forward AD of one unit's residual: its directions (AdPlan) kAdChunk at a time, the entries distributed to their
// columns, reductions added as outer products at the end.
void DaeSystem::reference_jacobian(double t, const double* y, const double* yp, double cj, double* dense) {
  if (inline_) throw std::logic_error("reference_jacobian: build the DaeSystem without inlining");
  fill_params(t);
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
    DenseSink sink(dense, n_, off);
    ad_unit(static_cast<int>(u), t, y, yp, cj, sink, &plain);
  }
}

void DaeSystem::ad_unit(int u, double t, const double* y, const double* yp, double cj, JacobianSink& sink,
                        const AdPlan* given) {
  const UnitInstance& inst = fs_.units()[u];
  const AdPlan& plan = given ? *given : *plans_[u];
  const auto& cols = local_cols_[u];
  const int ns = static_cast<int>(inst.spec.states().size()), off = inst.offset;
  (void)y, (void)yp;
  // An explicit unit's residual is x - f: its own columns are the identity.
  if (inst.spec.is_explicit())
    for (int k = 0; k < ns; ++k) sink.add(k, off + k, 1.0);
  std::unique_ptr<Recorder> rec;
  if (plan.recorded) rec = std::make_unique<Recorder>(plan, inst.name, cols.size(), ns);
  auto seed_dir = [&](const AdPlan::Dir& dir, size_t slot, double v, double vd) {
    if (dir.kind == AdPlan::kClass) {
      for (int c : plan.class_cols[dir.index])
        if (c >= 0) xj_[c].v[slot] = v, xdj_[c].v[slot] = vd;
    } else if (dir.kind == AdPlan::kCol) {
      xj_[cols[dir.index]].v[slot] = v, xdj_[cols[dir.index]].v[slot] = vd;
    }
  };
  for (size_t d0 = 0; d0 < plan.dirs.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(plan.dirs.size(), d0 + kAdChunk);
    // Seed: d/de F(y + e_j, y' + cj e_j) is column j of dF/dy + cj dF/dy'.
    for (size_t d = d0; d < d1; ++d) seed_dir(plan.dirs[d], d - d0, 1.0, cj);
    if (rec) rec->sweep(d0, d1);
    rj_.assign(ns, Jet(0.0));
    Ctx<Jet> c = ctx<Jet>(u, t, xj_.data(), xdj_.data(), pj_, rj_.data());
    c.recorder = rec.get();
    inst.unit->residual(c);
    for (size_t d = d0; d < d1; ++d) seed_dir(plan.dirs[d], d - d0, 0.0, 0.0);
    for (int k = 0; k < ns; ++k)
      for (size_t d = d0; d < d1; ++d) {
        const double v = rj_[k].v[d - d0];
        if (v == 0.0) continue;
        const AdPlan::Dir& dir = plan.dirs[d];
        if (dir.kind == AdPlan::kCol) {
          sink.add(k, cols[dir.index], v);
        } else if (dir.kind == AdPlan::kReduction) {
          rec->u(dir.index, k) += v;
        } else {
          const int i = plan.row_class[k];
          if (i < 0)
            throw std::logic_error("unit '" + inst.name + "': the equation of state '" + inst.spec.states()[k].name +
                                   "' reads per-class variables of every class directly; sum them with a reduction");
          if (plan.class_cols[dir.index][i] >= 0) sink.add(k, plan.class_cols[dir.index][i], v);
        }
      }
  }
  if (rec) rec->finish(cols, sink);
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

// Loads directions [d0, d1) into the Jets: the first n_loaded states' values and sensitivities (y' ones zero
// without `ypS`), and every unit's parameters seeded with the directions of the parameters they are or follow.
void DaeSystem::load_directions(const double* y, const double* yp, const std::vector<int>& params, size_t d0, size_t d1,
                                const double* const* yS, const double* const* ypS, int n_loaded) {
  jets_plain_ = 0;
  for (int i = 0; i < n_loaded; ++i) {
    xj_[i] = Jet(y[i]);
    xdj_[i] = Jet(yp[i]);
    for (size_t d = d0; d < d1; ++d) {
      xj_[i].v[d - d0] = yS[d][i];
      if (ypS) xdj_[i].v[d - d0] = ypS[d][i];
    }
  }
  params_as_jets();
  for (size_t u = 0; u < pj_.size(); ++u)
    for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj_[u]);
}

Status DaeSystem::sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                                const double* const* yS, const double* const* ypS, double* const* rS) {
  fill_params(t);
  const auto& units = fs_.units();
  rj_.assign(n_ext_, Jet(0.0));
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, ypS, n_);
    if (inline_) evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    for (size_t u = 0; u < units.size(); ++u) {
      if (inline_ && units[u].spec.is_explicit()) continue;
      const Status s = units[u].unit->residual(
          ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, rj_.data() + units[u].offset));
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

Status DaeSystem::quadrature(double t, const double* y, const double* yp, double* qdot) {
  fill_params(t);
  const auto& units = fs_.units();
  if (inline_) {
    std::copy(y, y + n_, y_ext_.begin());
    std::copy(yp, yp + n_, yp_ext_.begin());
    evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_, &quad_explicit_);
    y = y_ext_.data();
    yp = yp_ext_.data();
  }
  for (size_t u = 0; u < units.size(); ++u)
    if (!units[u].spec.quadratures().empty())
      units[u].unit->quadrature(ctx<double>(static_cast<int>(u), t, y, yp, pvals_, qdot + units[u].quad_offset));
  for (int i = 0; i < n_quad_; ++i)
    if (!std::isfinite(qdot[i])) return Status::kRecoverable;
  return Status::kOk;
}

Status DaeSystem::quadrature_sens(double t, const double* y, const double* yp, const std::vector<int>& params,
                                  const double* const* yS, double* const* qdotS) {
  fill_params(t);
  const auto& units = fs_.units();
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_);
    if (inline_) evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    qj_.assign(n_quad_, Jet(0.0));
    for (size_t u = 0; u < units.size(); ++u)
      if (!units[u].spec.quadratures().empty())
        units[u].unit->quadrature(
            ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, qj_.data() + units[u].quad_offset));
    for (size_t d = d0; d < d1; ++d)
      for (int i = 0; i < n_quad_; ++i) {
        qdotS[d][i] = qj_[i].v[d - d0];
        if (!std::isfinite(qdotS[d][i])) return Status::kRecoverable;
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
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_);
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
    if (units[u].shared >= 0) c.shared = pvals_[units[u].shared].data();
    c.work = ws_[u].get();
    units[u].unit->initial(c);
  }
  y0.resize(n_);  // explicit states, if inlined, are computed, not integrated
}

void DaeSystem::initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const {
  yS0.assign(params.size(), std::vector<double>(n_, 0.0));
  const auto& units = fs_.units();
  std::vector<std::vector<Jet>> pj(units.size());
  std::vector<Jet> x0(n_ext_);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    for (size_t u = 0; u < units.size(); ++u) {
      pj[u].resize(pvals_[u].size());
      for (size_t k = 0; k < pvals_[u].size(); ++k) pj[u][k] = Jet(pvals_[u][k]);
      for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj[u]);
    }
    for (size_t u = 0; u < units.size(); ++u) {
      InitCtx<Jet> c{pj[u].data(), x0.data() + units[u].offset};
      if (units[u].shared >= 0) c.shared = pj[units[u].shared].data();
      c.work = ws_[u].get();
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
  std::vector<double> s(n_ext_);
  for (int i = 0; i < n_ext_; ++i) s[i] = fs_.state_spec(i).scale;
  const auto& units = fs_.units();
  for (size_t u = 0; u < units.size(); ++u)
    units[u].unit->tolerance_scales(pvals_[u].data(), units[u].shared >= 0 ? pvals_[units[u].shared].data() : nullptr,
                                    s.data() + units[u].offset);
  s.resize(n_);
  return s;
}

std::vector<double> DaeSystem::quadrature_scales() const {
  std::vector<double> s;
  for (const auto& u : fs_.units())
    for (const auto& q : u.spec.quadratures()) s.push_back(q.scale);
  return s;
}

void DaeSystem::report(double t, const double* y, const double* yp, const double* q, double* out) {
  fill_params(t);
  const auto& units = fs_.units();
  int k = 0;
  for (size_t u = 0; u < units.size(); ++u) {
    const int no = static_cast<int>(units[u].spec.outputs().size());
    if (no == 0) continue;
    Ctx<double> c = ctx<double>(static_cast<int>(u), t, y, yp, pvals_, out + k);
    c.quad = q + units[u].quad_offset;
    units[u].unit->report(c);
    const auto& quads = units[u].spec.quadratures();
    for (size_t j = 0; j < quads.size(); ++j) out[k + quads[j].output.i] = q[units[u].quad_offset + j];
    k += no;
  }
}

void DaeSystem::report_sensitivities(double t, const double* y, const double* yp, const double* q,
                                     const std::vector<int>& params, const double* const* yS, const double* const* qS,
                                     double* const* dout) {
  fill_params(t);
  const auto& units = fs_.units();
  const int no = fs_.n_outputs();
  std::vector<Jet> out(no);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_ext_);
    for (int i = 0; i < n_quad_; ++i) {
      qj_[i] = Jet(q[i]);
      for (size_t d = d0; d < d1; ++d) qj_[i].v[d - d0] = qS ? qS[d][i] : 0.0;
    }
    std::fill(out.begin(), out.end(), Jet(0.0));
    int k = 0;
    for (size_t u = 0; u < units.size(); ++u) {
      const int nu = static_cast<int>(units[u].spec.outputs().size());
      if (nu == 0) continue;
      Ctx<Jet> c = ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, out.data() + k);
      c.quad = qj_.data() + units[u].quad_offset;
      units[u].unit->report(c);
      const auto& quads = units[u].spec.quadratures();
      for (size_t j = 0; j < quads.size(); ++j) out[k + quads[j].output.i] = qj_[units[u].quad_offset + j];
      k += nu;
    }
    for (size_t d = d0; d < d1; ++d)
      for (int j = 0; j < no; ++j) dout[d][j] = out[j].v[d - d0];
  }
}

std::string DaeSystem::describe_row(int row) const {
  const auto& u = fs_.units()[fs_.state_unit(row)];
  return "unit '" + u.name + "' (equation of state '" + u.spec.states()[row - u.offset].name + "')";
}

}  // namespace granuflow
