#include "liquid_mixer.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::units {
namespace {

class LiquidMixer : public UnitBase<LiquidMixer> {
 public:
  std::string type() const override { return "liquid_mixer"; }
  void declare(UnitSpec& s, Settings& settings) override {
    n_in_ = static_cast<int>(settings.get_int("inlets", 2, 2, 16, "number of inlet ports in1..inN"));
    s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    for (int i = 0; i < n_in_; ++i) s.add_port("in" + std::to_string(i + 1), StreamKind::Liquid, PortDir::In);
    out_ = s.add_port("out", StreamKind::Liquid, PortDir::Out);
    s.provide_all(out_, 0);
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    T m = T(0.0), mt = T(0.0), mw = T(0.0);
    for (int i = 0; i < n_in_; ++i) {
      const T& mi = c.port(i, liquid::kMdot);
      m += mi;
      mt += mi * c.port(i, liquid::kT);
      mw += mi * c.port(i, liquid::kW);
    }
    c.res(0) = c.x_(0) - m;             // mass balance
    c.res(1) = c.x_(0) * c.x_(1) - mt;  // enthalpy balance, constant cp
    c.res(2) = c.x_(0) * c.x_(2) - mw;  // solute balance
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[0] = T(0.1);
    c.x0[1] = T(300.0);
    c.x0[2] = T(0.0);
  }

 private:
  int n_in_ = 2, out_ = 0;
};

}  // namespace

void register_liquid_mixer(Registry<Unit>& r) {
  r.add("liquid_mixer", "adiabatic mixer of liquid streams", [] { return std::make_unique<LiquidMixer>(); });
}

}  // namespace granuflow::units
