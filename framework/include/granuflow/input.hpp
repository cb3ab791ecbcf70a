// Time-dependent inputs: piecewise-linear (or piecewise-constant, for steps) functions of time that replace a
// parameter's constant value. Their knots are breakpoints: the simulator stops there and re-initializes.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

class PiecewiseLinear {
 public:
  enum class Interp { kLinear, kStep };  // kStep: value of the last knot at or before t

  PiecewiseLinear() = default;
  // Throws ConfigError (naming `where`) unless times are strictly increasing and sizes agree.
  PiecewiseLinear(std::vector<double> times, std::vector<double> values, Interp interp, const std::string& where);
  static PiecewiseLinear constant(double v);

  double operator()(double t) const;  // constant extrapolation outside the knots
  // Exact integral over [a, b], used by tests and balance bookkeeping.
  double integral(double a, double b) const;
  const std::vector<double>& times() const { return t_; }
  const std::vector<double>& values() const { return v_; }
  Interp interp() const { return interp_; }

 private:
  std::vector<double> t_, v_;
  Interp interp_ = Interp::kLinear;
};

std::string to_string(PiecewiseLinear::Interp i);

}  // namespace granuflow
