// Forward AD of one unit's residual for the Jacobian: the plan of its seeded directions (class blocks, shared
// columns, reductions) and the recorder that turns reductions back into outer products.
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

#include "dae_internal.hpp"

namespace granuflow {

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

// Forward AD of one unit's residual: its directions (AdPlan) kAdChunk at a time, the entries distributed to their
// columns, reductions added as outer products at the end.
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
    drive_states(xj_.data(), pj_, u);  // driven parameters carry their sources' seeds
    drive_outputs(t, xj_.data(), xdj_.data(), pj_, u);
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

}  // namespace granuflow
