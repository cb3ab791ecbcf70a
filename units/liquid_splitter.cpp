#include "liquid_splitter.hpp"

namespace granuflow::units {
namespace {

class LiquidSplitter : public UnitBase<LiquidSplitter> {
 public:
  std::string type() const override { return "liquid_splitter"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param(
        {"split", "-", 0.5, 0.0, 1.0, "fraction of the inlet mass flow leaving through out1", "operating input"});
    const int m1 = s.add_state("mdot1", StateKind::Algebraic, "kg/s", 0.1);
    const int m2 = s.add_state("mdot2", StateKind::Algebraic, "kg/s", 0.1);
    const int t = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    const int w = s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.add_port("in", StreamKind::Liquid, PortDir::In);
    for (auto [name, m] : {std::pair{"out1", m1}, std::pair{"out2", m2}}) {
      const int p = s.add_port(name, StreamKind::Liquid, PortDir::Out);
      s.provide(p, liquid::kMdot, m);
      s.provide(p, liquid::kT, t);  // both outlets share the inlet's temperature and composition
      s.provide(p, liquid::kW, w);
    }
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m = c.port(0, liquid::kMdot);
    c.res(0) = c.x_(0) - c.par(0) * m;
    c.res(1) = c.x_(1) - (1.0 - c.par(0)) * m;
    c.res(2) = c.x_(2) - c.port(0, liquid::kT);
    c.res(3) = c.x_(3) - c.port(0, liquid::kW);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[0] = c.x0[1] = T(0.1);
    c.x0[2] = T(300.0);
    c.x0[3] = T(0.0);
  }
};

}  // namespace

void register_liquid_splitter(Registry<Unit>& r) {
  r.add("liquid_splitter", "splits a liquid stream in a set ratio", [] { return std::make_unique<LiquidSplitter>(); });
}

}  // namespace granuflow::units
