#include "aggregation/dem_collision.hpp"

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

void DemCollisionKernel::declare(Settings& s, const std::string& prefix) {
  auto names = table_names();
  if (names.empty()) names.push_back("(none loaded)");
  const std::string t = s.get_choice(prefix + "collisions", names.front(), names,
                                     "data table of DEM collision frequencies C_ij, 1/s (paper 002, Eq. (12))");
  frequency_ = &table(t);
  rule_ = s.get_choice(prefix + "wet_rule", "either", {"either", "both"},
                       "which partners must reach lc_min (paper 002, Eq. (13))") == "both"
              ? WetRule::kBoth
              : WetRule::kEither;
}

void DemCollisionKernel::check(const ClassState<double>& s, const double*, const std::string& where) const {
  if (frequency_->rows != s.n || frequency_->cols != s.n)
    throw ConfigError(where + ": collision table is " + std::to_string(frequency_->rows) + " x " +
                      std::to_string(frequency_->cols) + ", the grid has " + std::to_string(s.n) + " classes");
}

Table collision_frequency_table(const std::vector<double>& counts, const std::vector<double>& numbers, double dt,
                                const std::string& source) {
  const size_t n = numbers.size();
  if (counts.size() != n * n)
    throw ConfigError("collision counts: " + std::to_string(counts.size()) + " values for " + std::to_string(n) +
                      " classes (expected n x n)");
  if (!(dt > 0)) throw ConfigError(violation("collision window dt", dt, "s", "dt > 0"));
  Table t{static_cast<int>(n), static_cast<int>(n), std::vector<double>(n * n, 0.0), "1/s", source};
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j)
      if (numbers[i] > 0 && numbers[j] > 0) t.values[i * n + j] = counts[i * n + j] / (numbers[i] * numbers[j] * dt);
  return t;
}

void register_dem_collision(Registry<AggregationKernel>& r) {
  r.add("dem_collision", "DEM collision frequency x liquid-content efficiency (paper 002, Eqs. (11)-(13))",
        [] { return std::make_unique<DemCollisionKernel>(); });
}

}  // namespace granuflow::kernels
