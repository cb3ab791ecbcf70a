// PI controller (docs/controllers.md). Signals normalized by the measurement span y_span and the output range
// R = u_max - u_min, so the gain Kp is dimensionless whatever the two quantities are:
//   e = (y_sp - y) / y_span                     (reverse action: the output rises when y falls below the set point;
//                                                direct action: e = (y - y_sp) / y_span)
//   v = (u0 - u_min) / R + Kp e + I             output before the clamp, as a fraction of the range
//   u = u_min + R s(v),  s(v) = q(v) - q(v - 1),  q(x) = (x + sqrt(x^2 + eps^2)) / 2
//   dI/dt = Kp e / Ti + (s(v) - v) / Tt         integral action with back-calculation (Astrom & Hagglund 2006,
//                                                Advanced PID Control, Sec. 3.5, in normalized form)
// s is a smooth clamp to (0, 1): q is the smooth max(x, 0) the granulator's ideal controller uses for its valve, so
// s(v) stays strictly inside the range, is exact to eps^2 / 4 away from the limits and has a continuous slope for
// Newton. While the output is clamped, the tracking term pulls the integral back at the rate 1/Tt instead of letting
// it wind up.
#include "pi_controller.hpp"

#include <algorithm>
#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/renamed.hpp"
#include "granuflow/signals.hpp"

namespace granuflow::units {
namespace {

template <class T>
T smooth_max0(const T& x, const T& eps) {
  using std::sqrt;
  return 0.5 * (x + sqrt(x * x + eps * eps));
}

constexpr double kWide = 1e12;  // bounds of quantities whose range only the measured unit knows

class PiController : public UnitBase<PiController>, public SignalUnit, public HoldsSetPoint {
 public:
  std::string type() const override { return "pi_controller"; }
  void declare(UnitSpec& s, Settings& st) override {
    measure_ = st.get_choice("measure", "", {},
                             "the measured quantity: a state or reported output of another unit, as unit.name "
                             "(e.g. gas.T); the unit must be listed before the controller");
    drive_ = st.get_choice("drive", "", {},
                           "the parameter the controller sets: unit.param of another unit (e.g. inlet.T), listed "
                           "before the controller");
    direct_ =
        st.get_choice("action", "reverse", {"reverse", "direct"},
                      "reverse: the output rises when the measurement falls below the set point (heating); "
                      "direct: it rises when the measurement is above it (a discharge holding a level)") == "direct";
    const std::string ym = measure_.empty() ? "-" : measured_unit(st);
    ParamSpec u{"u0", "-", 0.0, -kWide, kWide, "", "docs/controllers.md"};
    if (!drive_.empty()) drive_ = driven_name(st);  // a deprecated spelling drives the parameter's new name
    if (!drive_.empty()) u = driven_spec(st);
    const std::string src = "docs/controllers.md";
    p_sp_ = s.add_param({"set_point", ym, 0.0, -kWide, kWide, "set point, in the unit of the measured quantity", src});
    p_span_ = s.add_param({"y_span", ym, 1.0, 1e-12, kWide,
                           "span of the measurement (its unit): the error enters as a fraction of it", src});
    p_kp_ = s.add_param({"Kp", "-", 1.0, 0.0, 1e6,
                         "proportional gain: output change, as a fraction of u_max - u_min, per error as a fraction "
                         "of y_span",
                         src});
    p_ti_ = s.add_param({"Ti", "s", 600.0, 1e-3, 1e9, "integral time", src});
    p_tt_ = s.add_param(
        {"Tt", "s", 600.0, 1e-3, 1e9, "tracking time of the anti-windup (back-calculation), of the order of Ti", src});
    p_umin_ = s.add_param({"u_min", u.unit, u.lower, u.lower, u.upper,
                           "lower limit of the output, in the unit of the driven parameter (bounds: its bounds)", src});
    p_umax_ = s.add_param({"u_max", u.unit, u.upper, u.lower, u.upper,
                           "upper limit of the output, in the unit of the driven parameter (bounds: its bounds)", src});
    p_u0_ = s.add_param({"u0", u.unit, u.value, u.lower, u.upper,
                         "output at zero error and zero integral (bias), the output the controller starts from", src});
    p_eps_ = s.add_param({"smoothing", "-", 1e-3, 1e-6, 0.1,
                          "width of the smoothed clamp at the limits, as a fraction of u_max - u_min", src});
    p_y_ = s.add_param({"measured", ym, 0.0, -kWide, kWide,
                        "the measured value, taken in every evaluation from the quantity named by setting measure "
                        "(cannot be set)",
                        src});
    sI_ = s.add_state("I", StateKind::Differential, "-", 0.01);
    sU_ = s.add_state("u", StateKind::Algebraic, u.unit,
                      std::max({std::abs(u.value), 1e-6 * (u.upper - u.lower), 1e-30}));
    o_y_ = s.add_output("measured", ym);
    o_dev_ = s.add_output("deviation", ym);
    o_i_ = s.add_output("integral", "-");
  }
  std::vector<Read> reads() const override { return {{p_y_, measure_, "measure"}}; }
  std::vector<Write> writes() const override { return {{sU_, drive_, "drive"}}; }
  std::vector<SetPoint> set_points() const override { return {{p_sp_, o_y_}}; }

  void check(const UnitSpec&, const double* p) const override {
    if (!(p[p_umin_.i] < p[p_umax_.i]))
      throw ConfigError(violation("u_min", p[p_umin_.i], "", "u_min < u_max (" + fmt_num(p[p_umax_.i]) + ")"));
    if (!(p[p_u0_.i] >= p[p_umin_.i] && p[p_u0_.i] <= p[p_umax_.i]))
      throw ConfigError(violation(
          "u0", p[p_u0_.i], "", "u_min <= u0 <= u_max (" + fmt_num(p[p_umin_.i]) + ", " + fmt_num(p[p_umax_.i]) + ")"));
  }
  void tolerance_scales(const double* p, const double*, double* scales) const override {
    scales[sU_.i] = std::max({std::abs(p[p_umin_.i]), std::abs(p[p_umax_.i]), 1e-30});
  }

  // Normalized error, output before the clamp and the clamped output (fractions of the range).
  template <class T>
  void law(const Ctx<T>& c, T& e, T& v, T& s) const {
    const T range = c.par(p_umax_) - c.par(p_umin_);
    e = (c.par(p_sp_) - c.par(p_y_)) / c.par(p_span_);
    if (direct_) e = -e;
    v = (c.par(p_u0_) - c.par(p_umin_)) / range + c.par(p_kp_) * e + c.x(sI_);
    s = smooth_max0(v, c.par(p_eps_)) - smooth_max0(T(v - 1.0), c.par(p_eps_));
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    T e, v, s;
    law(c, e, v, s);
    c.res(sU_) = c.x(sU_) - (c.par(p_umin_) + (c.par(p_umax_) - c.par(p_umin_)) * s);
    // Astrom & Hagglund (2006), Sec. 3.5: integral action with back-calculation tracking
    c.res(sI_) = c.xd(sI_) - (c.par(p_kp_) * e / c.par(p_ti_) + (s - v) / c.par(p_tt_));
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(sI_) = T(0.0);
    c.x(sU_) = c.par(p_u0_);  // a guess: the consistent start adds the proportional part
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_y_) = c.par(p_y_);
    c.out(o_dev_) = c.par(p_y_) - c.par(p_sp_);
    c.out(o_i_) = c.x(sI_);
  }

 private:
  std::pair<const UnitInstance*, std::string> named(Settings& st, const std::string& setting,
                                                    const std::string& value) const {
    const auto dot = value.find('.');
    const UnitInstance* u = dot == std::string::npos ? nullptr : st.unit(value.substr(0, dot));
    if (!u)
      throw ConfigError(st.where() + "." + setting + " = '" + value +
                        "': expected unit.name of a unit listed before the controller");
    return {u, value.substr(dot + 1)};
  }
  std::string measured_unit(Settings& st) const {
    const auto [u, name] = named(st, "measure", measure_);
    for (const auto& x : u->spec.states())
      if (u->state_prefix + x.name == measure_) return x.unit;
    for (const auto& o : u->spec.outputs())
      if (o.name == name) return o.unit;
    throw ConfigError(st.where() + ".measure = '" + measure_ + "': unit " + u->name + " has no state or output '" +
                      name + "'");
  }
  std::string driven_name(Settings& st) const {
    const auto [u, name] = named(st, "drive", drive_);
    if (u->spec.param_index(name) >= 0) return drive_;
    const std::string renamed = use_renamed_param(u->unit->type(), u->name, name);
    return renamed.empty() ? drive_ : u->name + "." + renamed;
  }
  ParamSpec driven_spec(Settings& st) const {
    const auto [u, name] = named(st, "drive", drive_);
    const int k = u->spec.param_index(name);
    if (k < 0)
      throw ConfigError(st.where() + ".drive = '" + drive_ + "': unit " + u->name + " has no parameter '" + name + "'");
    return u->spec.params()[k];
  }

  std::string measure_, drive_;
  bool direct_ = false;
  ParamId p_sp_, p_span_, p_kp_, p_ti_, p_tt_, p_umin_, p_umax_, p_u0_, p_eps_, p_y_;
  StateId sI_, sU_;
  OutputId o_y_, o_dev_, o_i_;
};

}  // namespace

void register_pi_controller(Registry<Unit>& r) {
  r.add("pi_controller",
        "PI controller with a clamped output and back-calculation anti-windup: measures a state or output of one "
        "unit and sets a parameter of another (docs/controllers.md)",
        [] { return std::make_unique<PiController>(); });
}

}  // namespace granuflow::units
