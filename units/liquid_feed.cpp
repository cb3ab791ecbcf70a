#include "liquid_feed.hpp"

namespace granuflow::units {
namespace {

class LiquidFeed : public UnitBase<LiquidFeed> {
 public:
  std::string type() const override { return "liquid_feed"; }
  void declare(UnitSpec& s, Settings&) override {
    s.add_param({"mdot", "kg/s", 0.1, 0.0, 1e3, "liquid mass flow", ""});
    s.add_param({"T", "K", 293.15, 200.0, 700.0, "liquid temperature", ""});
    s.add_param({"w", "kg/kg", 0.0, 0.0, 1.0, "dissolved-solids mass fraction", ""});
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.provide_all(s.add_port("out", StreamKind::Liquid, PortDir::Out), 0);
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.res(k) = c.x_(k) - c.par(k);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int k = 0; k < 3; ++k) c.x0[k] = c.p[k];
  }
};

}  // namespace

void register_liquid_feed(Registry<Unit>& r) {
  r.add("liquid_feed", "liquid source with set mass flow, temperature and solids fraction",
        [] { return std::make_unique<LiquidFeed>(); });
}

}  // namespace granuflow::units
