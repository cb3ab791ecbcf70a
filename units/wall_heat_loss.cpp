#include "wall_heat_loss.hpp"

#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

// Explicit: the heat flow follows the gas temperature; the energy lost is a quadrature.
class WallHeatLoss : public UnitBase<WallHeatLoss> {
 public:
  std::string type() const override { return "wall_heat_loss"; }
  void declare(UnitSpec& s, Settings&) override {
    namespace def = kernels::paper001::defaults;
    p_k_ = s.add_param({"k_wall", "W/(m2 K)", def::kWallHeatTransfer, 0.0, 1e3, "wall heat-transfer coefficient",
                        "paper 001, Table 8"});
    p_a_ = s.add_param({"A_wall", "m2", def::kWallArea, 0.0, 1e3, "wall surface", "paper 001, Table 6"});
    p_env_ = s.add_param({"T_env", "K", 293.15, 200.0, 400.0, "environment temperature", "docs/paper001_decisions.md"});
    sQ_ = s.add_state("Q", StateKind::Algebraic, "W", 1e3);
    s.set_explicit();
    in_ = s.add_port("in", streams::heat(), PortDir::In);
    s.provide(in_, heat::kQ, sQ_);  // the hot side provides its temperature
    q_lost_ = s.add_quadrature("balance_energy_out", "J", 1e6, OutputRole::kBalanceOut, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(sQ_) = c.x(sQ_) - c.par(p_k_) * c.par(p_a_) * (c.port(in_, heat::kT) - c.par(p_env_));  // Eq. (84), paper 001
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_lost_.i] = c.x(sQ_);
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sQ_) = T(0.0);
  }

 private:
  ParamId p_k_, p_a_, p_env_;
  StateId sQ_;
  PortId in_;
  QuadId q_lost_;
};

}  // namespace

void register_wall_heat_loss(Registry<Unit>& r) {
  r.add("wall_heat_loss", "heat loss through the wall to the environment (paper 001, Eq. 84)",
        [] { return std::make_unique<WallHeatLoss>(); });
}

}  // namespace granuflow::units
