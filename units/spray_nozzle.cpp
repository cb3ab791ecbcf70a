#include "spray_nozzle.hpp"

#include "granuflow/errors.hpp"
#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

// Explicit (its stream follows the parameters and the spray schedule); the amounts sprayed are quadratures.
class SprayNozzle : public UnitBase<SprayNozzle> {
 public:
  std::string type() const override { return "spray_nozzle"; }
  void declare(UnitSpec& s, Settings&) override {
    p_rate_ =
        s.add_param({"mdot", "kg/s", 90e-3 / 60.0, 0.0, 1.0, "liquid spray rate while spraying", "paper 001, Table 1"});
    p_t_ = s.add_param({"T", "K", kernels::paper001::defaults::kSprayTemperature, 273.15, 373.15, "liquid temperature",
                        "paper 001, Table 7"});
    p_w_ = s.add_param({"w", "kg/kg", 0.0, 0.0, 0.9, "dissolved-solids mass fraction of the liquid",
                        "paper 001: water spray (w = 0)"});
    p_on_ = s.add_param({"t_on", "s", 0.0, 0.0, 1e7, "spray start", "paper 001: spraying from the start"});
    p_off_ = s.add_param({"t_off", "s", 3600.0, 0.0, 1e7, "spray stop", "paper 001: 60 min of spraying"});
    sM_ = s.add_state("mdot", StateKind::Algebraic, "kg/s", 1e-3);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sW_ = s.add_state("w", StateKind::Algebraic, "kg/kg", 1.0);
    s.set_explicit();
    s.provide_all(s.add_port("out", streams::liquid(), PortDir::Out), sM_);
    q_water_ = s.add_quadrature("balance_water_in", "kg", 1.0, OutputRole::kBalanceIn, "water");
    q_solids_ = s.add_quadrature("balance_solids_in", "kg", 1.0, OutputRole::kBalanceIn, "solids");
    q_energy_ = s.add_quadrature("balance_energy_in", "J", 1e6, OutputRole::kBalanceIn, "energy");
  }
  void check(const UnitSpec&, const double* p) const override {
    if (p[p_off_.i] < p[p_on_.i])
      throw ConfigError(violation("t_off", p[p_off_.i], "s", "t_off >= t_on (" + fmt_num(p[p_on_.i]) + " s)"));
  }
  std::vector<double> breakpoints(const double* p) const override { return {p[p_on_.i], p[p_off_.i]}; }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    // On/off decided at the segment start: the integrator stops at t_on and t_off, so a segment never
    // straddles a switch.
    const bool on = c.t_seg >= value_of(c.par(p_on_)) && c.t_seg < value_of(c.par(p_off_));
    c.res(sM_) = c.x(sM_) - (on ? c.par(p_rate_) : T(0.0));
    c.res(sT_) = c.x(sT_) - c.par(p_t_);
    c.res(sW_) = c.x(sW_) - c.par(p_w_);
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_water_.i] = c.x(sM_) * (1.0 - c.x(sW_));
    c.r[q_solids_.i] = c.x(sM_) * c.x(sW_);
    // enthalpy above 0 degC; dissolved solids carried at the liquid heat capacity (w = 0 in paper 001)
    c.r[q_energy_.i] = c.x(sM_) * props::liquid_water_enthalpy(c.x(sT_));
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sM_) = value_of(c.par(p_on_)) <= 0.0 && value_of(c.par(p_off_)) > 0.0 ? c.par(p_rate_) : T(0.0);
    c.x(sT_) = c.par(p_t_);
    c.x(sW_) = c.par(p_w_);
  }

 private:
  ParamId p_rate_, p_t_, p_w_, p_on_, p_off_;
  StateId sM_, sT_, sW_;
  QuadId q_water_, q_solids_, q_energy_;
};

}  // namespace

void register_spray_nozzle(Registry<Unit>& r) {
  r.add("spray_nozzle", "spray liquid source with start and stop times",
        [] { return std::make_unique<SprayNozzle>(); });
}

}  // namespace granuflow::units
