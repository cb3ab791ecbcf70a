// A unit's scene settings: typed reads with defaults and bounds, and a refusal of any setting no unit read.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <set>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/quantity.hpp"

namespace granuflow {

Settings::Settings(std::string where, std::map<std::string, std::string> given)
    : where_(std::move(where)), given_(std::move(given)) {}

// Called right after the setting `name` was declared (declared_.back()).
const std::string* Settings::given(const std::string& name) {
  used_.push_back(name);
  const auto it = given_.find(name);
  for (const auto& [now, before] : renamed_) {
    if (name.compare(0, now.size(), now) != 0) continue;
    const std::string old = before + name.substr(now.size());
    declared_.back().old_name = old;
    const auto o = given_.find(old);
    if (o == given_.end()) break;
    used_.push_back(old);
    if (it != given_.end())
      throw ConfigError(where_ + ": both '" + old + "' and its new name '" + name + "' are given; keep '" + name + "'");
    static std::mutex mutex;
    static std::set<std::string> warned;
    std::lock_guard<std::mutex> lock(mutex);
    if (warned.insert(old).second)
      std::cerr << "granuflow: warning: setting '" << where_ << "." << old << "' is deprecated, it is now '" << name
                << "' (a kernel's setting has one name in every unit)\n";
    return &o->second;
  }
  return it == given_.end() ? nullptr : &it->second;
}

long Settings::get_int(const std::string& name, long def, long lower, long upper, const std::string& description) {
  declared_.push_back({name, SettingType::Int, def, {}, double(lower), double(upper), description, ""});
  const std::string* s = given(name);
  if (!s) return def;
  char* end = nullptr;
  const long v = std::strtol(s->c_str(), &end, 10);
  if (end == s->c_str() || *end != '\0')
    throw ConfigError(where_ + "." + name + " = '" + *s + "': expected an integer in [" + std::to_string(lower) + ", " +
                      std::to_string(upper) + "]");
  if (v < lower || v > upper)
    throw ConfigError(violation(where_ + "." + name, double(v), "",
                                std::to_string(lower) + " <= " + name + " <= " + std::to_string(upper)));
  declared_.back().value = v;  // the value in use, not only the default
  return v;
}

double Settings::get_real(const std::string& name, double def, double lower, double upper,
                          const std::string& description) {
  declared_.push_back({name, SettingType::Real, def, {}, lower, upper, description, ""});
  const std::string* s = given(name);
  if (!s) return def;
  const std::string where = where_ + "." + name + " = '" + *s + "'";
  double v = 0.0;
  std::string unit;
  if (!parse_quantity(*s, &v, &unit) || !std::isfinite(v))
    throw ConfigError(where + ": expected a finite number, optionally followed by a unit");
  // With a unit ("50 um"), as a parameter's value is read: converted once, here, to the SI unit the setting declares.
  if (!unit.empty()) {
    const std::string si = setting_si_unit(description);
    if (si.empty()) throw ConfigError(where + ": expected a plain number (this setting has no unit)");
    v = to_si(v, unit, si, where);
  }
  if (v < lower || v > upper)
    throw ConfigError(violation(where_ + "." + name, v, "", fmt_num(lower) + " <= " + name + " <= " + fmt_num(upper)));
  declared_.back().value = v;
  return v;
}

bool Settings::get_bool(const std::string& name, bool def, const std::string& description) {
  declared_.push_back({name, SettingType::Bool, def, {}, 0, 1, description, ""});
  const std::string* s = given(name);
  if (!s) return def;
  if (*s == "true" || *s == "on" || *s == "yes") return std::get<bool>(declared_.back().value = true);
  if (*s == "false" || *s == "off" || *s == "no") return std::get<bool>(declared_.back().value = false);
  throw ConfigError(where_ + "." + name + " = '" + *s + "': expected true or false");
}

std::string Settings::get_choice(const std::string& name, const std::string& def,
                                 const std::vector<std::string>& choices, const std::string& description) {
  declared_.push_back({name, SettingType::String, def, choices, 0, 0, description, ""});
  const std::string* s = given(name);
  if (!s) return def;
  if (!choices.empty() && std::find(choices.begin(), choices.end(), *s) == choices.end()) {
    std::string allowed;
    for (const auto& c : choices) allowed += (allowed.empty() ? "" : ", ") + c;
    throw ConfigError(where_ + "." + name + " = '" + *s + "': not one of the allowed values (" + allowed + ")");
  }
  declared_.back().value = *s;
  return *s;
}

const UnitInstance* Settings::unit(const std::string& name) const {
  if (!fs_) return nullptr;
  for (const auto& u : fs_->units())
    if (u.name == name) return &u;
  return nullptr;
}

void Settings::check_all_used() const {
  for (const auto& [k, v] : given_) {
    if (std::find(used_.begin(), used_.end(), k) != used_.end()) continue;
    std::string allowed;
    for (const auto& d : declared_) allowed += (allowed.empty() ? "" : ", ") + d.name;
    // A setting that belongs to another unit (the size grid, now the particle system's) names its place.
    std::string elsewhere;
    if (fs_)
      for (const auto& u : fs_->units())
        for (const auto& d : u.settings)
          if (d.name == k) elsewhere = u.name;
    throw ConfigError(where_ + "." + k + ": unknown setting (allowed: " + (allowed.empty() ? "none" : allowed) + ")" +
                      (elsewhere.empty() ? ""
                                         : "; '" + k + "' is a setting of " + elsewhere + ": set it under " +
                                               (elsewhere == "particles" ? "particles: settings:"
                                                                         : "units: " + elsewhere + ": settings:")));
  }
}

}  // namespace granuflow
