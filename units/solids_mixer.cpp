// Adiabatic mixer of solids streams, zero hold-up (explicit): per class, dry solids and water flows add up (and those
// of each named solid of a composed particle system, particles.hpp); the
// outlet temperature closes the enthalpy balance with constant heat capacities (solid cp_s of the particle system,
// water cp_l):
//     T_out - T0 = sum_j C_j (T_j - T0) / sum_j C_j,   C_j = sum_i (m_ji cp_s + w_ji cp_l),
// with a capacity flow of 1e-12 W/K at the first inlet's temperature added to both sums, so that the temperature of
// streams that carry nothing (a recycle at start-up) stays finite.
#include "solids_mixer.hpp"

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

constexpr double kCapacityFloor = 1e-12;  // W/K

struct Work : Workspace {
  template <class T>
  struct Flows {
    std::vector<T> m, w;    // per class: the flows summed over the inlets
    std::vector<T> cap, h;  // per class: capacity and enthalpy flows summed over the inlets
    std::vector<T> dt;      // per inlet: T_j - T0
    std::vector<T> gm, gw;  // an inlet's flows gathered where not consecutive (Ctx::port_array)
  };
  Flows<double> fd;
  Flows<Jet> fj;
};

class SolidsMixer : public UnitBase<SolidsMixer> {
 public:
  std::string type() const override { return "solids_mixer"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    pp_ = ps.params();
    n_ = ps.grid()->size();
    const int inlets = static_cast<int>(st.get_int("inlets", 2, 2, 16, "number of inlet ports in1..inN"));
    p_cpl_ = s.add_param({"cp_l", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 100.0, 1e4,
                          "heat capacity of the water carried", "paper 001, Table 6"});
    wet_ = ps.water();
    sM_ = s.add_states("mdot", n_, StateKind::Algebraic, "kg/s", 1e-2);
    if (wet_) sW_ = s.add_states("water", n_, StateKind::Algebraic, "kg/s", 1e-3);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    K_ = pp_.component_count();
    for (int k = 1; k < K_; ++k) sQ_.push_back(s.add_states(pp_.components[k], n_, StateKind::Algebraic, "kg/s", 1e-2));
    s.set_explicit();
    const auto& d = ps.grid()->diameter_pivots();
    ClassLayout layout{n_, {sM_}, {}};
    if (wet_) layout.state_blocks.push_back(sW_);
    for (StateId q : sQ_) layout.state_blocks.push_back(q);
    for (int j = 0; j < inlets; ++j) {
      const PortId p = s.add_port("in" + std::to_string(j + 1), streams::solids(K_), PortDir::In, n_);
      s.set_port_grid(p, d);
      in_.push_back(p);
      layout.field_blocks.push_back({p, solids::mdot(0)});
      if (wet_) layout.field_blocks.push_back({p, solids::water(n_, 0)});
      for (int k = 1; k < K_; ++k) layout.field_blocks.push_back({p, solids::component(n_, k, 0)});
    }
    const PortId out = s.add_port("out", streams::solids(K_), PortDir::Out, n_);
    s.set_port_grid(out, d);
    for (int k = 1; k < K_; ++k)
      for (int i = 0; i < n_; ++i) s.provide(out, solids::component(n_, k, i), sQ_[k - 1] + i);
    if (wet_) {
      for (int f = 0; f <= 2 * n_; ++f) s.provide(out, f, sM_ + f);  // mdot, water, T: consecutive states
    } else {  // every inlet's water is the same zero: the first one's passes on
      for (int i = 0; i < n_; ++i) s.provide(out, solids::mdot(i), sM_ + i);
      forward_dry_water(s, out, in_[0], n_);
      s.provide(out, solids::T(n_), sT_);
    }
    s.set_classes(layout);
    r_capacity_ = s.add_reduction("capacity flow");
    r_enthalpy_ = s.add_reduction("enthalpy flow");
    o_m_ = s.add_output("mdot", "kg/s");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    auto& f = per_scalar<T>(c.template ws<Work>().fd, c.template ws<Work>().fj);
    const T cp_s = c.sh(pp_.cp_s);
    const T& cp_l = c.par(p_cpl_);
    // one pass over the inlets' classes: flows, capacity flows C_ji and enthalpy flows C_ji (T_j - T0)
    f.dt.resize(in_.size());
    for (size_t j = 0; j < in_.size(); ++j) f.dt[j] = c.port(in_[j], solids::T(n_)) - props::kT0;
    flows(c, f, cp_s, cp_l);
    const T cap = c.reduce(r_capacity_, n_, [&](int i) { return f.cap[i]; });
    const T h = c.reduce(r_enthalpy_, n_, [&](int i) { return f.h[i]; });
    const T t_first = c.port(in_[0], solids::T(n_)) - props::kT0;
    c.res(sT_) = c.x(sT_) - (props::kT0 + (h + kCapacityFloor * t_first) / (cap + kCapacityFloor));
    return Status::kOk;
  }
  std::unique_ptr<Workspace> workspace() const override { return std::make_unique<Work>(); }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < n_; ++i) {
      c.x(sM_ + i) = T(0.0);
      if (wet_) c.x(sW_ + i) = T(0.0);
      for (StateId q : sQ_) c.x(q + i) = T(0.0);
    }
    c.x(sT_) = T(props::kT0 + 20.0);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    T m(0.0);
    for (int i = 0; i < n_; ++i) m += c.x(sM_ + i);
    c.out(o_m_) = m;
  }

 private:
  // Per class: the flows summed over the inlets in their order, capacity flows C = m cp_s + w cp_l and enthalpy
  // flows C (T_j - T0) (into f.cap, f.h), and the residuals; inlet by inlet over the classes, as arrays.
  template <class T, class F>
  void flows(const Ctx<T>& c, F& f, const T& cp_s, const T& cp_l) const {
    f.m.assign(n_, T(0.0)), f.w.assign(n_, T(0.0)), f.cap.assign(n_, T(0.0)), f.h.assign(n_, T(0.0));
    T *m = f.m.data(), *w = f.w.data(), *cap = f.cap.data(), *h = f.h.data();
    for (size_t j = 0; j < in_.size(); ++j) {
      const T* mp = c.port_array(in_[j], solids::mdot(0), n_, f.gm);
      const T& dt = f.dt[j];
      if (!wet_) {
        for (int i = 0; i < n_; ++i) {
          const T cp = mp[i] * cp_s;
          m[i] += mp[i], cap[i] += cp, h[i] += cp * dt;
        }
        continue;
      }
      const T* wp = c.port_array(in_[j], solids::water(n_, 0), n_, f.gw);
      for (int i = 0; i < n_; ++i) {
        const T cp = mp[i] * cp_s + wp[i] * cp_l;
        m[i] += mp[i], w[i] += wp[i], cap[i] += cp, h[i] += cp * dt;
      }
    }
    for (int i = 0; i < n_; ++i) c.res(sM_ + i) = c.x(sM_ + i) - m[i];
    if (wet_)
      for (int i = 0; i < n_; ++i) c.res(sW_ + i) = c.x(sW_ + i) - w[i];
    for (int k = 1; k < K_; ++k) {  // each further solid: the inlets' flows summed in their order
      T* r = &c.res(sQ_[k - 1]);
      const T* x = &c.x(sQ_[k - 1]);
      for (int i = 0; i < n_; ++i) r[i] = x[i];
      for (size_t j = 0; j < in_.size(); ++j) {
        const T* q = c.port_array(in_[j], solids::component(n_, k, 0), n_, f.gm);
        for (int i = 0; i < n_; ++i) r[i] -= q[i];
      }
    }
  }

  int n_ = 0;
  bool wet_ = true;  // the particle system carries water
  ParticleParams pp_;
  ParamId p_cpl_;
  std::vector<PortId> in_;
  StateId sM_, sW_, sT_;
  int K_ = 1;  // named solids; the flows of each after the first (sQ_[c - 1])
  std::vector<StateId> sQ_;
  ReductionId r_capacity_, r_enthalpy_;
  OutputId o_m_;
};

}  // namespace

void register_solids_mixer(Registry<Unit>& r) {
  r.add("solids_mixer", "adiabatic mixer of solids streams (class flows add, enthalpy balance for T)",
        [] { return std::make_unique<SolidsMixer>(); });
}

}  // namespace granuflow::units
