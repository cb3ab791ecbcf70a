#include "chamber_gas.hpp"

#include "granuflow/errors.hpp"
#include "granuflow/properties.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {
namespace {

class ChamberGas : public UnitBase<ChamberGas> {
 public:
  std::string type() const override { return "chamber_gas"; }
  void declare(UnitSpec& s, Settings&) override {
    p_mass_ = s.add_param({"m_gas", "kg", kernels::paper001::defaults::kGasHoldup, 1e-3, 1e4,
                           "dry-air hold-up of the chamber", "paper 001, Table 7; docs/paper001_decisions.md"});
    p_y0_ = s.add_param(
        {"Y0", "kg/kg", 0.005, 0.0, 0.5, "initial humidity", "docs/paper001_decisions.md: gas at inlet state"});
    p_t0_ = s.add_param(
        {"T0", "K", 333.15, 250.0, 600.0, "initial temperature", "docs/paper001_decisions.md: gas at inlet state"});
    sW_ = s.add_state("water", StateKind::Differential, "kg", 0.01);
    sH_ = s.add_state("enthalpy", StateKind::Differential, "J", 1e5);
    sY_ = s.add_state("Y", StateKind::Algebraic, "kg/kg", 0.01);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    in_ = s.add_port("in", streams::gas(), PortDir::In);
    evap_ = s.add_port("evap", streams::liquid(), PortDir::In, 0, true);      // spray evaporating in the gas
    drying_ = s.add_port("drying", streams::vapour(), PortDir::In, 0, true);  // vapour from drying particles
    wall_ = s.add_port("wall", streams::heat(), PortDir::Out, 0, true);       // heat leaving the gas
    solids_ = s.add_port("solids", streams::heat(), PortDir::Out, 0, true);
    s.provide(wall_, heat::kT, sT_);
    s.provide(solids_, heat::kT, sT_);
    // The dry-gas hold-up is constant: what flows out is what flows in, at the inlet pressure (passed on).
    for (const char* name : {"out", "state"}) {
      const PortId p = s.add_port(name, streams::gas(), std::string(name) == "out" ? PortDir::Out : PortDir::Probe);
      s.forward(p, gas::kMdot, in_, gas::kMdot);
      s.provide(p, gas::kY, sY_);
      s.provide(p, gas::kT, sT_);
      s.forward(p, gas::kP, in_, gas::kP);
    }
    o_rh_ = s.add_output("relative_humidity", "-");
    o_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
    o_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m_in = c.port(in_, gas::kMdot);
    const T& y_in = c.port(in_, gas::kY);
    const T& m_ev = c.port(evap_, liquid::kMdot);
    const T& m_dr = c.port(drying_, vapour::kMdot);
    // Eq. (61), paper 001, as a water-mass balance
    c.res(sW_) = c.xd(sW_) - (m_in * y_in - m_in * c.x(sY_) + m_ev + m_dr);
    // Eq. (62), paper 001, conservative: inflows at their own enthalpy; the evaporating spray enters as
    // liquid, so the gas supplies its sensible and latent heat (docs/paper001_decisions.md sign)
    c.res(sH_) = c.xd(sH_) - (m_in * props::humid_air_enthalpy(c.port(in_, gas::kT), y_in) -
                              m_in * props::humid_air_enthalpy(c.x(sT_), c.x(sY_)) +
                              m_ev * props::liquid_water_enthalpy(c.port(evap_, liquid::kT)) +
                              m_dr * props::vapour_enthalpy(c.port(drying_, vapour::kT)) - c.port(wall_, heat::kQ) -
                              c.port(solids_, heat::kQ));
    c.res(sY_) = c.x(sW_) - c.par(p_mass_) * c.x(sY_);
    c.res(sT_) = c.x(sH_) - c.par(p_mass_) * props::humid_air_enthalpy(c.x(sT_), c.x(sY_));  // Eq. (63)
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sY_) = c.par(p_y0_);
    c.x(sT_) = c.par(p_t0_);
    c.x(sW_) = c.par(p_mass_) * c.par(p_y0_);
    c.x(sH_) = c.par(p_mass_) * props::humid_air_enthalpy(c.par(p_t0_), c.par(p_y0_));
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    // Only water can evaporate into the gas: a spray that carries dissolved solids (its w) must deposit them first
    // (droplet_evaporation's vapour carries none). Checked on the solution at the output times, not in the residual,
    // whose states a finite-difference Jacobian perturbs.
    if (value_of(c.port(evap_, liquid::kW)) > 0.0 && value_of(c.port(evap_, liquid::kMdot)) > 0.0)
      throw ConfigError("chamber_gas, port evap: the liquid evaporating into the gas carries dissolved solids (w = " +
                        fmt_num(value_of(c.port(evap_, liquid::kW))) +
                        " kg/kg) that the gas cannot hold; allowed: w = 0 (pass a solution through a "
                        "droplet_evaporation unit, whose vapour is water)");
    c.out(o_rh_) = props::relative_humidity(c.x(sY_), c.x(sT_), c.port(in_, gas::kP));
    c.out(o_water_) = c.x(sW_);
    c.out(o_energy_) = c.x(sH_);
  }

 private:
  ParamId p_mass_, p_y0_, p_t0_;
  StateId sW_, sH_, sY_, sT_;
  PortId in_, evap_, drying_, wall_, solids_;
  OutputId o_rh_, o_water_, o_energy_;
};

}  // namespace

void register_chamber_gas(Registry<Unit>& r) {
  r.add("chamber_gas", "well-mixed chamber gas: vapour and enthalpy balances (paper 001, Eqs. 61-63)",
        [] { return std::make_unique<ChamberGas>(); });
}

}  // namespace granuflow::units
