#include "granuflow/quantity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "granuflow/errors.hpp"

namespace granuflow {
namespace {

struct UnitAlias {
  const char* name;
  const char* si;
  double factor;  // si = factor * value + offset
  double offset;
};

// Every SI unit maps to itself; the others are the units the papers and plants use.
const UnitAlias kAliases[] = {
    {"-", "-", 1, 0},
    {"%", "-", 0.01, 0},
    {"K", "K", 1, 0},
    {"degC", "K", 1, 273.15},
    {"m", "m", 1, 0},
    {"mm", "m", 1e-3, 0},
    {"um", "m", 1e-6, 0},
    {"cm", "m", 1e-2, 0},
    {"m2", "m2", 1, 0},
    {"m3", "m3", 1, 0},
    {"L", "m3", 1e-3, 0},
    {"kg", "kg", 1, 0},
    {"g", "kg", 1e-3, 0},
    {"s", "s", 1, 0},
    {"min", "s", 60, 0},
    {"h", "s", 3600, 0},
    {"1/s", "1/s", 1, 0},
    {"1/min", "1/s", 1.0 / 60, 0},
    {"1/h", "1/s", 1.0 / 3600, 0},
    {"kg/s", "kg/s", 1, 0},
    {"g/min", "kg/s", 1e-3 / 60, 0},
    {"g/s", "kg/s", 1e-3, 0},
    {"kg/h", "kg/s", 1.0 / 3600, 0},
    {"kg/min", "kg/s", 1.0 / 60, 0},
    {"m3/s", "m3/s", 1, 0},
    {"m3/h", "m3/s", 1.0 / 3600, 0},
    {"L/min", "m3/s", 1e-3 / 60, 0},
    {"m/s", "m/s", 1, 0},
    {"kg/kg", "kg/kg", 1, 0},
    {"g/kg", "kg/kg", 1e-3, 0},
    {"wt%", "kg/kg", 0.01, 0},
    {"kg/m3", "kg/m3", 1, 0},
    {"g/L", "kg/m3", 1, 0},
    {"Pa", "Pa", 1, 0},
    {"kPa", "Pa", 1e3, 0},
    {"bar", "Pa", 1e5, 0},
    {"W", "W", 1, 0},
    {"kW", "W", 1e3, 0},
    {"J", "J", 1, 0},
    {"kJ", "J", 1e3, 0},
    {"J/kg", "J/kg", 1, 0},
    {"kJ/kg", "J/kg", 1e3, 0},
    {"J/(kg K)", "J/(kg K)", 1, 0},
    {"kJ/(kg K)", "J/(kg K)", 1e3, 0},
    {"W/(m2 K)", "W/(m2 K)", 1, 0},
    {"W/(m K)", "W/(m K)", 1, 0},
    {"m2/s", "m2/s", 1, 0},
    {"Pa s", "Pa s", 1, 0},
    {"mPa s", "Pa s", 1e-3, 0},
    {"J/kg/m", "J/kg/m", 1, 0},
    {"1/m", "1/m", 1, 0},
    {"kg/(m2 s)", "kg/(m2 s)", 1, 0},
    {"m3/kg", "m3/kg", 1, 0},
    {"kg/mol", "kg/mol", 1, 0},
    {"g/mol", "kg/mol", 1e-3, 0},
    {"m3/(s kg)", "m3/(s kg)", 1, 0},
    {"kg/m2", "kg/m2", 1, 0},
    {"1/J", "1/J", 1, 0},
    {"J/kg K", "J/(kg K)", 1, 0},
    {"m^3/s", "m3/s", 1, 0},
    {"1/(m s)", "1/(m s)", 1, 0},
    {"1/m3", "1/m3", 1, 0},
};

const UnitAlias* find_alias(const std::string& name) {
  for (const auto& a : kAliases)
    if (name == a.name) return &a;
  return nullptr;
}

}  // namespace

const std::vector<std::string>& known_si_units() {
  static const std::vector<std::string> units = [] {
    std::vector<std::string> v;
    for (const auto& a : kAliases)
      if (std::find(v.begin(), v.end(), a.si) == v.end()) v.push_back(a.si);
    return v;
  }();
  return units;
}

bool is_known_si_unit(const std::string& si_unit) {
  const auto& u = known_si_units();
  return std::find(u.begin(), u.end(), si_unit) != u.end();
}

double to_si(double value, const std::string& from_unit, const std::string& si_unit, const std::string& where) {
  if (from_unit.empty() || from_unit == si_unit) return value;
  const UnitAlias* a = find_alias(from_unit);
  if (!a) {
    std::string allowed;
    for (const auto& x : kAliases)
      if (si_unit == x.si) allowed += (allowed.empty() ? "" : ", ") + std::string(x.name);
    throw ConfigError(where + ": unknown unit '" + from_unit + "' (allowed for " + si_unit + ": " + allowed + ")");
  }
  if (si_unit != a->si)
    throw ConfigError(where + ": unit '" + from_unit + "' is " + a->si + ", but the value must be in " + si_unit);
  return a->factor * value + a->offset;
}

bool parse_quantity(const std::string& text, double* value, std::string* unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin) return false;
  std::string rest(end);
  const auto first = rest.find_first_not_of(" \t");
  rest = first == std::string::npos ? "" : rest.substr(first, rest.find_last_not_of(" \t") - first + 1);
  *value = v;
  *unit = rest;
  return true;
}

}  // namespace granuflow
