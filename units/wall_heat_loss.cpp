#include "wall_heat_loss.hpp"

#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

enum P { kK, kA, kTEnv };
enum S { kQ, kLost };

class WallHeatLoss : public UnitBase<WallHeatLoss> {
 public:
  std::string type() const override { return "wall_heat_loss"; }
  void declare(UnitSpec& s, Settings&) override {
    namespace def = kernels::paper001::defaults;
    s.add_param({"k_wall", "W/(m2 K)", def::kWallHeatTransfer, 0.0, 1e3, "wall heat-transfer coefficient",
                 "paper 001, Table 8"});
    s.add_param({"A_wall", "m2", def::kWallArea, 0.0, 1e3, "wall surface", "paper 001, Table 6"});
    s.add_param({"T_env", "K", 293.15, 200.0, 400.0, "environment temperature", "docs/paper001_decisions.md"});
    s.add_state("Q", StateKind::Algebraic, "W", 1e3);
    s.add_state("energy_lost", StateKind::Differential, "J", 1e6);
    const int p = s.add_port("in", StreamKind::Heat, PortDir::In);
    s.provide(p, heat::kQ, kQ);  // the hot side provides its temperature
    s.add_output("balance_energy_out", "J");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(kQ) = c.x_(kQ) - c.par(kK) * c.par(kA) * (c.port(0, heat::kT) - c.par(kTEnv));  // Eq. (84), paper 001
    c.res(kLost) = c.xd(kLost) - c.x_(kQ);
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x0[kQ] = T(0.0);
    c.x0[kLost] = T(0.0);
  }
  void report(const Ctx<double>& c, double* out) const override { out[0] = c.x_(kLost); }
};

}  // namespace

void register_wall_heat_loss(Registry<Unit>& r) {
  r.add("wall_heat_loss", "heat loss through the wall to the environment (paper 001, Eq. 84)",
        [] { return std::make_unique<WallHeatLoss>(); });
}

}  // namespace granuflow::units
