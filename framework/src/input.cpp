#include "granuflow/input.hpp"

#include <algorithm>
#include <cmath>

#include "granuflow/errors.hpp"

namespace granuflow {

PiecewiseLinear::PiecewiseLinear(std::vector<double> times, std::vector<double> values, Interp interp,
                                 const std::string& where)
    : t_(std::move(times)), v_(std::move(values)), interp_(interp) {
  if (t_.empty() || t_.size() != v_.size())
    throw ConfigError(where + ": an input needs as many times as values and at least one (got " +
                      std::to_string(t_.size()) + " times, " + std::to_string(v_.size()) + " values)");
  for (size_t i = 0; i < t_.size(); ++i) {
    if (!std::isfinite(t_[i]) || !std::isfinite(v_[i]))
      throw ConfigError(where + ": knot " + std::to_string(i) + " is not finite");
    if (i > 0 && !(t_[i] > t_[i - 1]))
      throw ConfigError(violation(where + ".times[" + std::to_string(i) + "]", t_[i], "s",
                                  "times strictly increasing (previous " + std::to_string(t_[i - 1]) + ")"));
  }
}

PiecewiseLinear PiecewiseLinear::constant(double v) { return PiecewiseLinear({0.0}, {v}, Interp::kLinear, "constant"); }

double PiecewiseLinear::operator()(double t) const {
  if (t <= t_.front()) return v_.front();
  if (t >= t_.back()) return v_.back();
  const size_t k = std::upper_bound(t_.begin(), t_.end(), t) - t_.begin();  // t_[k-1] <= t < t_[k]
  if (interp_ == Interp::kStep) return v_[k - 1];
  const double w = (t - t_[k - 1]) / (t_[k] - t_[k - 1]);
  return v_[k - 1] + w * (v_[k] - v_[k - 1]);
}

double PiecewiseLinear::integral(double a, double b) const {
  if (b < a) return -integral(b, a);
  // Integrate exactly over the pieces between the sorted cut points.
  std::vector<double> cuts{a};
  for (double tk : t_)
    if (tk > a && tk < b) cuts.push_back(tk);
  cuts.push_back(b);
  double s = 0.0;
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double lo = cuts[i], hi = cuts[i + 1];
    if (interp_ == Interp::kStep) {
      s += (*this)(lo) * (hi - lo);  // value is constant on [lo, hi)
    } else {
      s += 0.5 * ((*this)(lo) + (*this)(hi)) * (hi - lo);  // linear on [lo, hi]
    }
  }
  return s;
}

std::string to_string(PiecewiseLinear::Interp i) { return i == PiecewiseLinear::Interp::kStep ? "step" : "linear"; }

}  // namespace granuflow
