#include "liquid_splitter.hpp"

namespace granuflow::units {
namespace {

// Explicit: the two flows follow the inlet's; temperature and composition are passed on unchanged.
class LiquidSplitter : public UnitBase<LiquidSplitter> {
 public:
  std::string type() const override { return "liquid_splitter"; }
  void declare(UnitSpec& s, Settings&) override {
    p_split_ = s.add_param(
        {"split", "-", 0.5, 0.0, 1.0, "fraction of the inlet mass flow leaving through out1", "operating input"});
    s1_ = s.add_state("mdot1", StateKind::Algebraic, "kg/s", 0.1);
    s2_ = s.add_state("mdot2", StateKind::Algebraic, "kg/s", 0.1);
    in_ = s.add_port("in", streams::liquid(), PortDir::In);
    for (auto [name, m] : {std::pair{"out1", s1_}, std::pair{"out2", s2_}}) {
      const PortId p = s.add_port(name, streams::liquid(), PortDir::Out);
      s.provide(p, liquid::kMdot, m);
      s.forward(p, liquid::kT, in_, liquid::kT);
      s.forward(p, liquid::kW, in_, liquid::kW);
    }
    s.set_explicit();
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m = c.port(in_, liquid::kMdot);
    c.res(s1_) = c.x(s1_) - c.par(p_split_) * m;
    c.res(s2_) = c.x(s2_) - (1.0 - c.par(p_split_)) * m;
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(s1_) = c.x(s2_) = T(0.1);
  }

 private:
  ParamId p_split_;
  StateId s1_, s2_;
  PortId in_;
};

}  // namespace

void register_liquid_splitter(Registry<Unit>& r) {
  r.add("liquid_splitter", "splits a liquid stream in a set ratio", [] { return std::make_unique<LiquidSplitter>(); });
}

}  // namespace granuflow::units
