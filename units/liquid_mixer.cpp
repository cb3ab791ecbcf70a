#include "liquid_mixer.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::units {
namespace {

class LiquidMixer : public UnitBase<LiquidMixer> {
 public:
  std::string type() const override { return "liquid_mixer"; }
  void declare(UnitSpec& s, Settings& settings) override {
    n_in_ = static_cast<int>(settings.get_int("inlets", 2, 2, 16, "number of inlet ports in1..inN"));
    sM_ = s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sW_ = s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    for (int i = 0; i < n_in_; ++i)
      in_.push_back(s.add_port("in" + std::to_string(i + 1), streams::liquid(), PortDir::In));
    s.provide_all(s.add_port("out", streams::liquid(), PortDir::Out), sM_);
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    T m = T(0.0), mt = T(0.0), mw = T(0.0);
    for (PortId p : in_) {
      const T& mi = c.port(p, liquid::kMdot);
      m += mi;
      mt += mi * c.port(p, liquid::kT);
      mw += mi * c.port(p, liquid::kW);
    }
    c.res(sM_) = c.x(sM_) - m;              // mass balance
    c.res(sT_) = c.x(sM_) * c.x(sT_) - mt;  // enthalpy balance, constant cp
    c.res(sW_) = c.x(sM_) * c.x(sW_) - mw;  // solute balance
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sM_) = T(0.1);
    c.x(sT_) = T(300.0);
    c.x(sW_) = T(0.0);
  }

 private:
  int n_in_ = 2;
  std::vector<PortId> in_;
  StateId sM_, sT_, sW_;
};

}  // namespace

void register_liquid_mixer(Registry<Unit>& r) {
  r.add("liquid_mixer", "adiabatic mixer of liquid streams", [] { return std::make_unique<LiquidMixer>(); });
}

}  // namespace granuflow::units
