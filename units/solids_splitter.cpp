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
    K_ = ps.params().component_count();
    in_ = s.add_port("in", streams::solids(K_), PortDir::In, n_);
    out_.declare(s, ps, in_, {"out1", "out2"});
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& f = c.par(p_f_);
    for (int i = 0; i < n_; ++i) {
      const T& m = c.port(in_, solids::mdot(i));
      c.res(out_.m[0] + i) = c.x(out_.m[0] + i) - f * m;
      c.res(out_.m[1] + i) = c.x(out_.m[1] + i) - (m - f * m);
      if (!out_.wet) continue;
      const T& w = c.port(in_, solids::water(n_, i));
      c.res(out_.w[0] + i) = c.x(out_.w[0] + i) - f * w;
      c.res(out_.w[1] + i) = c.x(out_.w[1] + i) - (w - f * w);
    }
    for (int k = 1; k < K_; ++k)
      for (int i = 0; i < n_; ++i) {
        const T& q = c.port(in_, solids::component(n_, k, i));
        const StateId q0 = out_.q[0][k - 1], q1 = out_.q[1][k - 1];
        c.res(q0 + i) = c.x(q0 + i) - f * q;
        c.res(q1 + i) = c.x(q1 + i) - (q - f * q);
      }
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    out_.init(c, n_);
  }

 private:
  int n_ = 0;
  int K_ = 1;  // named solids
  ParamId p_f_;
  PortId in_;
  SolidsOutlets out_;
};

}  // namespace

void register_solids_splitter(Registry<Unit>& r) {
  r.add("solids_splitter", "splits a solids stream in two by a fixed fraction, every class alike",
        [] { return std::make_unique<SolidsSplitter>(); });
}

}  // namespace granuflow::units
