#include "gas_inlet.hpp"

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"

namespace granuflow::units {
namespace {

// Explicit: the stream's fields are functions of the parameters only, so they add no unknowns (inlined); the
// water and energy fed are quadratures.
class GasInlet : public UnitBase<GasInlet> {
 public:
  std::string type() const override { return "gas_inlet"; }
  void declare(UnitSpec& s, Settings& settings) override {
    normal_basis_ = settings.get_choice("flow_basis", "inlet", {"inlet", "normal"},
                                        "volume flow measured at the inlet temperature and pressure (default, "
                                        "docs/paper001_decisions.md) or at 0 degC and 1 atm") == "normal";
    p_vdot_ = s.add_param({"V_dot", "m3/s", 700.0 / 3600.0, 0.0, 100.0, "air volume flow", "paper 001, Table 1"});
    p_t_ = s.add_param({"T", "K", 333.15, 250.0, 600.0, "air temperature", "paper 001, Table 1"});
    p_y_ = s.add_param(
        {"Y", "kg/kg", 0.005, 0.0, 0.5, "absolute humidity, kg water per kg dry air", "docs/paper001_decisions.md"});
    p_p_ = s.add_param({"p", "Pa", props::kPressureAtm, 5e4, 5e5, "pressure", "docs/paper001_decisions.md"});
    sM_ = s.add_state("mdot", StateKind::Algebraic, "kg/s", 0.2);
    sY_ = s.add_state("Y", StateKind::Algebraic, "kg/kg", 0.01);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sP_ = s.add_state("p", StateKind::Algebraic, "Pa", 1e5);
    s.set_explicit();
    s.provide_all(s.add_port("out", streams::gas(), PortDir::Out), sM_);
    s.provide_all(s.add_port("state", streams::gas(), PortDir::Probe), sM_);
    o_vdot_ = s.add_output("V_dot", "m3/s");
    q_water_ = s.add_quadrature("balance_water_in", "kg", 10.0, OutputRole::kBalanceIn, "water");
    q_energy_ = s.add_quadrature("balance_energy_in", "J", 1e7, OutputRole::kBalanceIn, "energy");
  }
  // Dry-air mass flow of the volume flow V_dot on the chosen basis (docs/paper001_decisions.md: inlet state).
  template <class T>
  T dry_mass_flow(const T* p) const {
    const T t_basis = normal_basis_ ? T(props::kT0) : p[p_t_.i];
    const T p_basis = normal_basis_ ? T(props::kPressureAtm) : p[p_p_.i];
    return p[p_vdot_.i] * props::dry_air_partial_density(t_basis, p_basis, p[p_y_.i]);
  }
  // Air holding more water than saturation would condense at once, which no unit models: the integrator would
  // grind on it until it gives up. Antoine, Eq. (69) of paper 001, gives the saturation humidity, Eq. (68).
  void check(const UnitSpec&, const double* p) const override {
    // Above the boiling point (p_sat >= p) no humidity saturates the air.
    if (props::saturation_pressure(p[p_t_.i]) >= p[p_p_.i]) return;
    const double y_sat = props::equilibrium_humidity(p[p_t_.i], p[p_p_.i]);
    if (!(p[p_y_.i] <= y_sat))
      throw ConfigError(violation("Y", p[p_y_.i], "kg/kg",
                                  "Y <= saturation humidity " + fmt_num(y_sat) + " kg/kg (relative humidity " +
                                      fmt_num(100.0 * props::relative_humidity(p[p_y_.i], p[p_t_.i], p[p_p_.i])) +
                                      " %) at T = " + fmt_num(p[p_t_.i]) + " K and p = " + fmt_num(p[p_p_.i]) +
                                      " Pa: the inlet air must not be supersaturated"));
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    c.res(sM_) = c.x(sM_) - dry_mass_flow(c.p);
    c.res(sY_) = c.x(sY_) - c.par(p_y_);
    c.res(sT_) = c.x(sT_) - c.par(p_t_);
    c.res(sP_) = c.x(sP_) - c.par(p_p_);
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    c.r[q_water_.i] = c.x(sM_) * c.x(sY_);
    c.r[q_energy_.i] = c.x(sM_) * props::humid_air_enthalpy(c.x(sT_), c.x(sY_));
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sM_) = dry_mass_flow(c.p);
    c.x(sY_) = c.par(p_y_);
    c.x(sT_) = c.par(p_t_);
    c.x(sP_) = c.par(p_p_);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_vdot_) = c.par(p_vdot_);
  }

 private:
  bool normal_basis_ = false;
  ParamId p_vdot_, p_t_, p_y_, p_p_;
  StateId sM_, sY_, sT_, sP_;
  OutputId o_vdot_;
  QuadId q_water_, q_energy_;
};

}  // namespace

void register_gas_inlet(Registry<Unit>& r) {
  r.add("gas_inlet", "fluidization air: volume flow, temperature, humidity",
        [] { return std::make_unique<GasInlet>(); });
}

}  // namespace granuflow::units
