#include "aggregation/dem_collision.hpp"

#include <cmath>

#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

void DemCollisionKernel::declare(Settings& s, const std::string& prefix) {
  rule_ = s.get_choice(prefix + "wet_rule", "either", {"either", "both"},
                       "which partners must reach lc_min (paper 002, Eq. (13))") == "both"
              ? WetRule::kBoth
              : WetRule::kEither;
  shape_ = s.get_choice(prefix + "efficiency", "step", {"step", "smooth"},
                        "efficiency in the liquid content: the step of Eq. (13), paper 002, or a logistic of width "
                        "lc_width") == "smooth"
               ? EfficiencyShape::kSmooth
               : EfficiencyShape::kStep;
  const std::string file =
      s.get_choice(prefix + "collisions_file", "", {},
                   "CSV of collision counts from a DEM run (docs/dem_collisions.md); relative to the scene's folder");
  if (!file.empty()) {
    try {
      counts_ = std::make_shared<const CollisionCounts>(read_collision_counts(resolve_data_path(s.where(), file)));
    } catch (const ConfigError& e) {  // the file's own message (row, column) after the scene key that named it
      throw ConfigError(s.where() + "." + prefix + "collisions_file = '" + file + "': " + e.what());
    }
    owned_ = std::make_shared<const Table>(collision_frequency_table(*counts_));
    frequency_ = owned_.get();
  } else {
    auto names = table_names();
    const bool none = names.empty();
    if (none) names.push_back("(none loaded)");
    const std::string t = s.get_choice(prefix + "collisions", names.front(), names,
                                       "data table of DEM collision frequencies C_ij, 1/s (paper 002, Eq. (12)); "
                                       "used when no collisions_file is given");
    if (none)  // nothing to choose from: the setting that is missing is the file
      throw ConfigError(
          s.where() + "." + prefix +
          "collisions_file: not given, and no table of collision frequencies is loaded; name the DEM "
          "collision-count file (CSV: like_collisions, dt_s, edges_m, particles, counts; docs/dem_collisions.md)");
    frequency_ = &table(t);
  }
}

void DemCollisionKernel::check(const ClassState<double>& s, const double*, const std::string& where) const {
  if (counts_) {
    for (int i = 0; i < s.n; ++i)
      if (counts_->class_of(s.diameter[i]) < 0)
        throw ConfigError(where + ": class " + std::to_string(i) + " (pivot diameter " + fmt_num(s.diameter[i]) +
                          " m) lies outside the DEM classes of " + counts_->path + " (edges " +
                          fmt_num(counts_->edges.front()) + " to " + fmt_num(counts_->edges.back()) +
                          " m); widen the file's edges_m or shorten the grid");
    return;
  }
  if (frequency_->rows != s.n || frequency_->cols != s.n)
    throw ConfigError(where + ": collision table is " + std::to_string(frequency_->rows) + " x " +
                      std::to_string(frequency_->cols) + ", the grid has " + std::to_string(s.n) + " classes");
}

int DemCollisionKernel::efficiency_terms(const double* phi, int n, const double* p, double* h, double* sign) const {
  if (rule_ == WetRule::kBoth) {
    for (int i = 0; i < n; ++i) h[i] = wet(phi[i], p);
    sign[0] = 1.0;
    return 1;
  }
  for (int i = 0; i < n; ++i) h[i] = 1.0, h[n + i] = 1.0 - wet(phi[i], p);
  sign[0] = 1.0, sign[1] = -1.0;
  return 2;
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
      if (numbers[i] > 0 && numbers[j] > 0) {
        const double c = counts[i * n + j] / (numbers[i] * numbers[j] * dt);
        if (!std::isfinite(c))  // counts near the largest double, particle numbers near the smallest
          throw ConfigError(source + ": the collision frequency of classes " + std::to_string(i + 1) + " x " +
                            std::to_string(j + 1) + " (Eq. (12): count / (F_i F_j dt)) is not a finite number");
        t.values[i * n + j] = c;
      }
  return t;
}

// The population balance's event rate within class i is 1/2 C_ii F_i^2, between i != j C_ij F_i F_j: Eq. (12) as
// printed gives that when N_ii holds each like collision twice; a file that counts it once has its diagonal doubled.
Table collision_frequency_table(const CollisionCounts& c) {
  if (c.like_tally == 2) return collision_frequency_table(c.counts, c.particles, c.dt, c.path);
  std::vector<double> counts = c.counts;
  const size_t n = c.particles.size();
  for (size_t i = 0; i < n; ++i) counts[i * n + i] *= 2.0;
  return collision_frequency_table(counts, c.particles, c.dt, c.path);
}

void register_dem_collision(Registry<AggregationKernel>& r) {
  r.add("dem_collision", "DEM collision frequency x liquid-content efficiency (paper 002, Eqs. (11)-(13))",
        [] { return std::make_unique<DemCollisionKernel>(); });
}

}  // namespace granuflow::kernels
