// Mill without hold-up (explicit): out_i = sum_k P_ik in_k for the dry solids and for the water they carry, P the
// comminution law's mass-transfer matrix (kernels/comminution/comminution_law.hpp: columns sum to one, so mass is
// conserved to round-off), and likewise for each named solid after the first of a composed particle system
// (particles.hpp: a fragment keeps its parent's composition); the temperature passes through (the grinding energy is
// not accounted for).
//
// Every outlet class reads every coarser inlet class, so the class-coloured AD of the framework does not apply; the
// unit supplies its whole Jacobian (the identity on its own states, -P on the inlet), which is the matrix itself.
#include "mill.hpp"

#include <Eigen/Dense>
#include <algorithm>

#include "granuflow/flowsheet.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/registry.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

struct Work : Workspace {
  std::vector<double> key, P;
  std::vector<Jet> P_jet, scratch;
  template <class T>
  struct Flows {
    std::vector<T> in_m, in_w, m, w;  // the inlet gathered where not consecutive (Ctx::port_array); the outlet sums
  };
  Flows<double> fd;
  Flows<Jet> fj;
};

class Mill : public UnitBase<Mill> {
 public:
  std::string type() const override { return "mill"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    grid_ = ps.grid();
    n_ = grid_->size();
    const auto& reg = kernels::registries().comminution;
    law_ = reg.create(st.get_choice("law", "lognormal", reg.names(), "comminution law"), st.where());
    law_->declare(st, "");
    first_ = static_cast<int>(s.params().size());
    for (const ParamSpec& p : law_->params()) s.add_param(p);
    count_ = static_cast<int>(s.params().size()) - first_;
    sM_ = s.add_states("mdot", n_, StateKind::Algebraic, "kg/s", 1e-2);
    wet_ = ps.water();
    if (wet_) sW_ = s.add_states("water", n_, StateKind::Algebraic, "kg/s", 1e-3);
    K_ = ps.params().component_count();
    for (int k = 1; k < K_; ++k)
      sQ_.push_back(s.add_states(ps.params().components[k], n_, StateKind::Algebraic, "kg/s", 1e-2));
    s.set_explicit();
    s.set_analytic_part(true);
    const auto& d = grid_->diameter_pivots();
    in_ = s.add_port("in", streams::solids(K_), PortDir::In, n_);
    s.set_port_grid(in_, d);
    const PortId out = s.add_port("out", streams::solids(K_), PortDir::Out, n_);
    s.set_port_grid(out, d);
    for (int i = 0; i < n_; ++i) {
      s.provide(out, solids::mdot(i), sM_ + i);
      if (wet_) s.provide(out, solids::water(n_, i), sW_ + i);
    }
    if (!wet_) forward_dry_water(s, out, in_, n_);
    s.forward(out, solids::T(n_), in_, solids::T(n_));
    for (int k = 1; k < K_; ++k)
      for (int i = 0; i < n_; ++i) s.provide(out, solids::component(n_, k, i), sQ_[k - 1] + i);
    o_m_ = s.add_output("mdot", "kg/s");
    o_d50_in_ = s.add_output("d50_in", "m");
    o_d50_out_ = s.add_output("d50_out", "m");
  }
  std::unique_ptr<Workspace> workspace() const override { return std::make_unique<Work>(); }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T* P = matrix(c);
    auto& f = per_scalar<T>(c.template ws<Work>().fd, c.template ws<Work>().fj);
    f.m.assign(n_, T(0.0)), f.w.assign(n_, T(0.0));
    const T* in_m = c.port_array(in_, solids::mdot(0), n_, f.in_m);
    if (!wet_) f.in_w.assign(n_, T(0.0));
    const T* in_w = wet_ ? c.port_array(in_, solids::water(n_, 0), n_, f.in_w) : f.in_w.data();
    if constexpr (std::is_same_v<T, double>) {
      const bool wet = std::any_of(in_w, in_w + n_, [](double v) { return v != 0.0; });
      if (law_->parent_independent()) {
        // Every coarser parent puts the same share P_i,n-1 on class i: a suffix sum over the parents (O(n))
        parent_independent_product(P, in_m, f.m.data());
        if (wet) parent_independent_product(P, in_w, f.w.data());
      } else {
        // Eigen's blocked triangular product (P is upper triangular: parent class k feeds classes i <= k); a dry
        // feed skips the water column, which would be a second product of zeros
        const Eigen::Map<const Eigen::MatrixXd> Pm(P, n_, n_);
        Eigen::Map<Eigen::VectorXd>(f.m.data(), n_).noalias() =
            Pm.triangularView<Eigen::Upper>() * Eigen::Map<const Eigen::VectorXd>(in_m, n_);
        if (wet)
          Eigen::Map<Eigen::VectorXd>(f.w.data(), n_).noalias() =
              Pm.triangularView<Eigen::Upper>() * Eigen::Map<const Eigen::VectorXd>(in_w, n_);
      }
    } else {
      for (int k = 0; k < n_; ++k) {  // column by column (P is column-major)
        const T* col = P + size_t(k) * n_;
        for (int i = 0; i <= k; ++i) f.m[i] += col[i] * in_m[k], f.w[i] += col[i] * in_w[k];
      }
    }
    for (int i = 0; i < n_; ++i) c.res(sM_ + i) = c.x(sM_ + i) - f.m[i];
    if (wet_)
      for (int i = 0; i < n_; ++i) c.res(sW_ + i) = c.x(sW_ + i) - f.w[i];
    for (int k = 1; k < K_; ++k) {  // each further solid by the same matrix, column by column
      const T* in_q = c.port_array(in_, solids::component(n_, k, 0), n_, f.in_w);
      f.m.assign(n_, T(0.0));
      for (int j = 0; j < n_; ++j) {
        const T* col = P + size_t(j) * n_;
        for (int i = 0; i <= j; ++i) f.m[i] += col[i] * in_q[j];
      }
      for (int i = 0; i < n_; ++i) c.res(sQ_[k - 1] + i) = c.x(sQ_[k - 1] + i) - f.m[i];
    }
    return Status::kOk;
  }
  void analytic_jacobian(const Ctx<double>& c, double, JacobianSink& sink) const override {
    const double* P = matrix(c);
    const auto& ports = *c.port_index;
    for (int i = 0; i < n_; ++i) {
      sink.add(sM_.i + i, c.offset + sM_.i + i, 1.0);
      if (wet_) sink.add(sW_.i + i, c.offset + sW_.i + i, 1.0);
      for (StateId q : sQ_) sink.add(q.i + i, c.offset + q.i + i, 1.0);
      for (int k = i; k < n_; ++k) {
        const double a = P[size_t(k) * n_ + i];
        if (a == 0.0) continue;
        const int cm = ports[in_.i][solids::mdot(k)], cw = wet_ ? ports[in_.i][solids::water(n_, k)] : -1;
        if (cm >= 0) sink.add(sM_.i + i, cm, -a);
        if (cw >= 0) sink.add(sW_.i + i, cw, -a);
        for (int q = 1; q < K_; ++q) {
          const int cq = ports[in_.i][solids::component(n_, q, k)];
          if (cq >= 0) sink.add(sQ_[q - 1].i + i, cq, -a);
        }
      }
    }
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < n_; ++i) c.x(sM_ + i) = T(0.0);
    if (wet_)
      for (int i = 0; i < n_; ++i) c.x(sW_ + i) = T(0.0);
    for (StateId q : sQ_)
      for (int i = 0; i < n_; ++i) c.x(q + i) = T(0.0);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    std::vector<T> in(n_), out(n_);
    T m(0.0);
    for (int i = 0; i < n_; ++i) in[i] = c.port(in_, solids::mdot(i)), out[i] = c.x(sM_ + i), m += out[i];
    c.out(o_m_) = m;
    const auto& de = grid_->diameter_edges();
    // undefined (not 0) while nothing flows
    c.out(o_d50_in_) = kernels::characteristic_diameter_of_mass(de, in.data(), 0.5);
    c.out(o_d50_out_) = kernels::characteristic_diameter_of_mass(de, out.data(), 0.5);
  }

 private:
  // out = P in for a law whose fragments do not depend on the parent: out_i = P_ii in_i + P_i,n-1 sum_{k > i} in_k.
  void parent_independent_product(const double* P, const double* in, double* out) const {
    const double* last = P + size_t(n_ - 1) * n_;  // column n - 1: P_i,n-1 = P_ik for every parent k > i
    double coarser = 0.0;                          // sum_{k > i} in_k
    for (int i = n_ - 1; i >= 0; --i) {
      out[i] = P[size_t(i) * n_ + i] * in[i] + last[i] * coarser;
      coarser += in[i];
    }
  }
  // The law's matrix for this evaluation: cached per parameter values for doubles; recomputed in Jets when a law
  // parameter carries a derivative.
  const double* matrix(const Ctx<double>& c) const {
    Work& w = c.template ws<Work>();
    refresh(w, c.p + first_);
    return w.P.data();
  }
  const Jet* matrix(const Ctx<Jet>& c) const {
    Work& w = c.template ws<Work>();
    bool derivative = false;
    for (int k = first_; k < first_ + count_; ++k) derivative = derivative || !c.p[k].v.isZero();
    if (derivative) {
      w.scratch.resize(size_t(n_) * n_);
      law_->matrix(grid_->diameter_edges(), grid_->diameter_pivots(), c.p + first_, w.scratch.data());
      return w.scratch.data();
    }
    std::vector<double> v(count_);
    for (int k = 0; k < count_; ++k) v[k] = c.p[first_ + k].a;
    refresh(w, v.data());
    return w.P_jet.data();
  }
  void refresh(Work& w, const double* p) const {
    if (!w.P.empty() && std::equal(w.key.begin(), w.key.end(), p)) return;
    w.key.assign(p, p + count_);
    w.P.resize(size_t(n_) * n_);
    law_->matrix(grid_->diameter_edges(), grid_->diameter_pivots(), p, w.P.data());
    w.P_jet.resize(w.P.size());
    for (size_t k = 0; k < w.P.size(); ++k) w.P_jet[k] = Jet(w.P[k]);
  }

  int n_ = 0, first_ = 0, count_ = 0;
  bool wet_ = true;  // the particle system carries water
  std::shared_ptr<const kernels::Grid> grid_;
  std::unique_ptr<kernels::ComminutionLaw> law_;
  PortId in_;
  StateId sM_, sW_;
  int K_ = 1;  // named solids; the flows of each after the first (sQ_[c - 1])
  std::vector<StateId> sQ_;
  OutputId o_m_, o_d50_in_, o_d50_out_;
};

}  // namespace

void register_mill(Registry<Unit>& r) {
  r.add("mill", "mill: a comminution law spreads each class over finer ones, mass conserved exactly (paper 003)",
        [] { return std::make_unique<Mill>(); });
}

}  // namespace granuflow::units
