// A unit written to lose mass, for the balance guard's test (tests/python/test_balance_guard.py): a liquid pipe
// that passes on only (1 - leak) of its inlet flow and reports the rest nowhere, as a unit with a bookkeeping bug
// would. Built with the tests into the unit library and registered only when the environment variable
// GRANUFLOW_TEST_UNITS is set (units/registry.cpp), so that no shipped scene, reference page or unit list sees it.
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"

namespace granuflow::units {
namespace {

class LeakyPipe : public UnitBase<LeakyPipe> {
 public:
  std::string type() const override { return "test_leaky_pipe"; }
  void declare(UnitSpec& s, Settings&) override {
    p_leak_ = s.add_param({"leak", "-", 0.05, 0.0, 1.0, "fraction of the inlet flow lost unreported", "test only"});
    sM_ = s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    in_ = s.add_port("in", streams::liquid(), PortDir::In);
    const PortId out = s.add_port("out", streams::liquid(), PortDir::Out);
    s.provide(out, liquid::kMdot, sM_);
    s.forward(out, liquid::kT, in_, liquid::kT);
    s.forward(out, liquid::kW, in_, liquid::kW);
    s.set_explicit();
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(sM_) = c.x(sM_) - (1.0 - c.par(p_leak_)) * c.port(in_, liquid::kMdot);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sM_) = T(0.1);
  }

 private:
  ParamId p_leak_;
  StateId sM_;
  PortId in_;
};

}  // namespace

void register_test_units(Registry<Unit>& r) {
  r.add("test_leaky_pipe", "test only: a liquid pipe that loses a fraction of its flow unreported",
        [] { return std::make_unique<LeakyPipe>(); });
}

}  // namespace granuflow::units
