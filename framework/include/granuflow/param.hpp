// Parameters and settings, declared once per unit in code with SI unit and bounds.
// Parameters are numbers that may change between runs without rebuilding (and may be calibrated, swept,
// differentiated, or driven by a piecewise-linear input). Settings shape the structure (class count, kernel
// name, a mechanism on or off): changing one rebuilds the flowsheet.
#pragma once
#include <string>
#include <variant>
#include <vector>

namespace granuflow {

struct ParamSpec {
  std::string name;  // local name; addressed from outside as "unit.name"
  std::string unit;  // SI unit from the checked set in quantity.hpp
  double value;      // default
  double lower;      // inclusive bounds; validation and calibration use them
  double upper;
  std::string description;
  std::string source;  // e.g. "paper 001, Table 9"
};

enum class SettingType { Int, Real, Bool, String };

using SettingValue = std::variant<long, double, bool, std::string>;

struct SettingSpec {
  std::string name;
  SettingType type;
  SettingValue value;                // the value in use: the default unless the scene gives one
  std::vector<std::string> choices;  // for String: the allowed values (empty = any)
  double lower = -1e300;             // for Int and Real
  double upper = 1e300;
  std::string description;
  std::string old_name;  // a deprecated spelling still accepted (Settings::rename_prefix), or ""
};

std::string to_string(SettingType t);
std::string setting_to_string(const SettingValue& v);

}  // namespace granuflow
