#include "liquid_feed.hpp"

#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

// Explicit source; the amounts fed are quadratures.
class LiquidFeed : public UnitBase<LiquidFeed> {
 public:
  std::string type() const override { return "liquid_feed"; }
  void declare(UnitSpec& s, Settings&) override {
    p_m_ = s.add_param({"mdot", "kg/s", 0.1, 0.0, 1e3, "liquid mass flow", "operating input"});
    p_t_ = s.add_param({"T", "K", 293.15, 200.0, 700.0, "liquid temperature", "operating input"});
    p_w_ = s.add_param({"w", "kg/kg", 0.0, 0.0, 1.0, "dissolved-solids mass fraction", "operating input"});
    p_cp_ = s.add_param({"cp", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 1.0, 1e5,
                         "heat capacity for the enthalpy account (above 0 degC)", "water, paper 001, Table 6"});
    sM_ = s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.1);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sW_ = s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.set_explicit();
    s.provide_all(s.add_port("out", streams::liquid(), PortDir::Out), sM_);
    q_water_ = s.add_quadrature("balance_water_in", "kg", 100.0, OutputRole::kBalanceIn, "water");
    q_solids_ = s.add_quadrature("balance_solids_in", "kg", 1.0, OutputRole::kBalanceIn, "solids");
    q_energy_ = s.add_quadrature("balance_energy_in", "J", 1e8, OutputRole::kBalanceIn, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(sM_) = c.x(sM_) - c.par(p_m_);
    c.res(sT_) = c.x(sT_) - c.par(p_t_);
    c.res(sW_) = c.x(sW_) - c.par(p_w_);
    return Status::kOk;
  }
  // The water balance counts the whole liquid (solvent and solute), as the tank's hold-up does.
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_water_.i] = c.x(sM_);
    c.r[q_solids_.i] = c.x(sM_) * c.x(sW_);
    c.r[q_energy_.i] = c.x(sM_) * props::liquid_water_enthalpy(c.x(sT_), c.par(p_cp_));
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sM_) = c.par(p_m_);
    c.x(sT_) = c.par(p_t_);
    c.x(sW_) = c.par(p_w_);
  }

 private:
  ParamId p_m_, p_t_, p_w_, p_cp_;
  StateId sM_, sT_, sW_;
  QuadId q_water_, q_solids_, q_energy_;
};

}  // namespace

void register_liquid_feed(Registry<Unit>& r) {
  r.add("liquid_feed", "liquid source with set mass flow, temperature and solids fraction",
        [] { return std::make_unique<LiquidFeed>(); });
}

}  // namespace granuflow::units
