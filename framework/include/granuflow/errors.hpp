// Typed errors of granuflow: one channel (exceptions) at the API boundary.
// ConfigError -> Python ValueError, SolverError -> Python granuflow.SolverError (RuntimeError).
#pragma once
#include <sstream>
#include <stdexcept>
#include <string>

namespace granuflow {

// Bad input: a scene key, a parameter value, an unknown name. The message names where, what, value, rule.
class ConfigError : public std::invalid_argument {
 public:
  explicit ConfigError(const std::string& msg) : std::invalid_argument(msg) {}
};

// The integrator or nonlinear solver gave up. Carries the time, the unit with the worst residual and its value.
class SolverError : public std::runtime_error {
 public:
  SolverError(const std::string& msg, double t, std::string unit, double worst_residual)
      : std::runtime_error(msg), t_(t), unit_(std::move(unit)), worst_residual_(worst_residual) {}
  double t() const { return t_; }
  const std::string& unit() const { return unit_; }
  double worst_residual() const { return worst_residual_; }

 private:
  double t_;
  std::string unit_;
  double worst_residual_;
};

class CalibrationError : public std::runtime_error {
 public:
  explicit CalibrationError(const std::string& msg) : std::runtime_error(msg) {}
};

// A number for a message: %g-style, shortest form up to 12 significant digits ("1800", "0.01", "5e-05"),
// never std::to_string's fixed "%f" (which shows 1e-9 as "0.000000").
inline std::string fmt_num(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

// Message template "where = value unit: violates rule" (Ceres OPTION_GE style).
// User text inside a message: one line, control bytes escaped, at most 60 characters shown (yaml_text.cpp).
std::string shown(const std::string& text);

inline std::string violation(const std::string& where, double value, const std::string& unit, const std::string& rule) {
  std::ostringstream os;
  os.precision(12);
  os << where << " = " << value << (unit.empty() || unit == "-" ? "" : " " + unit) << ": violates " << rule;
  return os.str();
}

}  // namespace granuflow
