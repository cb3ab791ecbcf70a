// Splitter of a solids stream, zero hold-up (explicit): out1 takes the fraction `fraction` of every class's solids
// and water (and of each named solid of a composed particle system, particles.hpp), out2 the rest (computed as the
// difference, so the two add up to the inlet to one rounding); the temperature passes through to both.
#include "solids_splitter.hpp"

#include <string>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

class SolidsSplitter : public UnitBase<SolidsSplitter> {
 public:
  std::string type() const override { return "solids_splitter"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    n_ = ps.grid()->size();
    p_f_ = s.add_param({"fraction", "-", 0.5, 0.0, 1.0, "fraction of the inlet sent to out1", "operating input"});
    const auto& d = ps.grid()->diameter_pivots();
    K_ = ps.params().component_count();
    in_ = s.add_port("in", streams::solids(K_), PortDir::In, n_);
    s.set_port_grid(in_, d);
    wet_ = ps.water();
    for (int o = 0; o < 2; ++o) {
      sM_[o] = s.add_states("out" + std::to_string(o + 1) + "_mdot", n_, StateKind::Algebraic, "kg/s", 1e-2);
      if (wet_) sW_[o] = s.add_states("out" + std::to_string(o + 1) + "_water", n_, StateKind::Algebraic, "kg/s", 1e-3);
      for (int k = 1; k < K_; ++k)
        sQ_[o].push_back(s.add_states("out" + std::to_string(o + 1) + "_" + ps.params().components[k], n_,
                                      StateKind::Algebraic, "kg/s", 1e-2));
    }
    s.set_explicit();
    for (int o = 0; o < 2; ++o) {
      const PortId out = s.add_port("out" + std::to_string(o + 1), streams::solids(K_), PortDir::Out, n_);
      s.set_port_grid(out, d);
      for (int i = 0; i < n_; ++i) {
        s.provide(out, solids::mdot(i), sM_[o] + i);
        if (wet_) s.provide(out, solids::water(n_, i), sW_[o] + i);
      }
      if (!wet_) forward_dry_water(s, out, in_, n_);
      s.forward(out, solids::T(n_), in_, solids::T(n_));
      for (int k = 1; k < K_; ++k)
        for (int i = 0; i < n_; ++i) s.provide(out, solids::component(n_, k, i), sQ_[o][k - 1] + i);
    }
    ClassLayout layout;
    if (wet_)
      layout = {n_, {sM_[0], sW_[0], sM_[1], sW_[1]}, {{in_, solids::mdot(0)}, {in_, solids::water(n_, 0)}}};
    else
      layout = {n_, {sM_[0], sM_[1]}, {{in_, solids::mdot(0)}}};
    for (int k = 1; k < K_; ++k) {
      layout.state_blocks.push_back(sQ_[0][k - 1]), layout.state_blocks.push_back(sQ_[1][k - 1]);
      layout.field_blocks.push_back({in_, solids::component(n_, k, 0)});
    }
    s.set_classes(layout);
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& f = c.par(p_f_);
    for (int i = 0; i < n_; ++i) {
      const T& m = c.port(in_, solids::mdot(i));
      c.res(sM_[0] + i) = c.x(sM_[0] + i) - f * m;
      c.res(sM_[1] + i) = c.x(sM_[1] + i) - (m - f * m);
      if (!wet_) continue;
      const T& w = c.port(in_, solids::water(n_, i));
      c.res(sW_[0] + i) = c.x(sW_[0] + i) - f * w;
      c.res(sW_[1] + i) = c.x(sW_[1] + i) - (w - f * w);
    }
    for (int k = 1; k < K_; ++k)
      for (int i = 0; i < n_; ++i) {
        const T& q = c.port(in_, solids::component(n_, k, i));
        c.res(sQ_[0][k - 1] + i) = c.x(sQ_[0][k - 1] + i) - f * q;
        c.res(sQ_[1][k - 1] + i) = c.x(sQ_[1][k - 1] + i) - (q - f * q);
      }
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int o = 0; o < 2; ++o)
      for (int i = 0; i < n_; ++i) {
        c.x(sM_[o] + i) = T(0.0);
        if (wet_) c.x(sW_[o] + i) = T(0.0);
        for (StateId q : sQ_[o]) c.x(q + i) = T(0.0);
      }
  }

 private:
  int n_ = 0;
  bool wet_ = true;  // the particle system carries water
  ParamId p_f_;
  PortId in_;
  StateId sM_[2], sW_[2];
  int K_ = 1;  // named solids; per outlet the flows of each after the first (sQ_[o][c - 1])
  std::vector<StateId> sQ_[2];
};

}  // namespace

void register_solids_splitter(Registry<Unit>& r) {
  r.add("solids_splitter", "splits a solids stream in two by a fixed fraction, every class alike",
        [] { return std::make_unique<SolidsSplitter>(); });
}

}  // namespace granuflow::units
