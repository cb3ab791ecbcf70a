#include "data_tables.hpp"

#include <cmath>
#include <map>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {
namespace {
std::map<std::string, Table>& store() {
  static std::map<std::string, Table> tables;
  return tables;
}
}  // namespace

void set_table(const std::string& name, Table t) {
  if (t.rows < 1 || t.cols < 1 || t.values.size() != size_t(t.rows) * t.cols)
    throw ConfigError("table '" + name + "': " + std::to_string(t.values.size()) + " values for " +
                      std::to_string(t.rows) + " x " + std::to_string(t.cols));
  for (double v : t.values)
    if (!std::isfinite(v)) throw ConfigError(violation("table '" + name + "' value", v, t.unit, "finite"));
  store()[name] = std::move(t);
}

const Table& table(const std::string& name) {
  auto it = store().find(name);
  if (it != store().end()) return it->second;
  std::string names;
  for (const auto& [k, v] : store()) names += (names.empty() ? "" : ", ") + k;
  throw ConfigError("unknown data table '" + name + "' (loaded: " + (names.empty() ? "none" : names) + ")");
}

std::vector<std::string> table_names() {
  std::vector<std::string> v;
  for (const auto& [k, t] : store()) v.push_back(k);
  return v;
}

}  // namespace granuflow::kernels
