#include "discretization/grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr int kMinClasses = 2;  // the virtual pivots extrapolate from two pivots at each end
}  // namespace

double diameter_of_volume(double v) { return std::cbrt(6.0 * v / kPi); }
double volume_of_diameter(double d) { return kPi / 6.0 * d * d * d; }

Grid::Grid(std::vector<double> edges, std::vector<double> pivots)
    : edges_(std::move(edges)), pivots_(std::move(pivots)) {
  const int n = size();
  if (n < kMinClasses || static_cast<int>(edges_.size()) != n + 1)
    throw ConfigError(violation("grid classes", n, "", "classes >= " + std::to_string(kMinClasses)));
  for (int i = 0; i < n; ++i) {
    if (!(edges_[i] > 0) || !(edges_[i] < pivots_[i] && pivots_[i] < edges_[i + 1]) || !std::isfinite(edges_[i + 1]))
      throw ConfigError(violation("grid pivot " + std::to_string(i), pivots_[i], "m3",
                                  "0 < e_i < x_i < e_{i+1} (increasing, finite edges)"));
  }
  for (double e : edges_) d_edges_.push_back(diameter_of_volume(e));
  for (double x : pivots_) d_pivots_.push_back(diameter_of_volume(x));
  x_lo_ = pivots_[0] * pivots_[0] / pivots_[1];
  x_hi_ = pivots_[n - 1] * pivots_[n - 1] / pivots_[n - 2];
  // The virtual pivots, the kernels and the moments square the volumes: a grid whose end pivots' squares leave the
  // doubles (a doubling grid of 525 classes from 2^-12 m3 reaches 2e154 m3) gave NaN rates at t = 0.
  if (!std::isfinite(x_hi_))
    throw ConfigError(violation("grid pivot " + std::to_string(n - 1), pivots_[n - 1], "m3",
                                "pivot^2 finite (pivots below 1.3e154 m3): fewer classes or a smaller volume range"));
  if (!(pivots_[0] * pivots_[0] >= std::numeric_limits<double>::min()))
    throw ConfigError(violation("grid pivot 0", pivots_[0], "m3",
                                "pivot^2 a normal double (pivots above 1.5e-154 m3): a larger smallest volume"));
}

Grid Grid::geometric(double v_min, int q, int classes) {
  if (!(v_min > 0) || !std::isfinite(v_min)) throw ConfigError(violation("grid v_min", v_min, "m3", "v_min > 0"));
  if (q < 1) throw ConfigError(violation("grid q", q, "", "q >= 1 (volume ratio 2^(1/q))"));
  if (classes < kMinClasses)
    throw ConfigError(violation("grid classes", classes, "", "classes >= " + std::to_string(kMinClasses)));
  std::vector<double> e(classes + 1);
  // Powers of 2 by exp2 (not repeated products), so the doubling grid of q = 1 is exact: x_j + x_j = x_{j+1}.
  for (int i = 0; i <= classes; ++i) e[i] = v_min * std::exp2(double(i) / q);
  return from_edges(std::move(e));
}

Grid Grid::from_edges(std::vector<double> e) {
  std::vector<double> x;
  for (size_t i = 0; i + 1 < e.size(); ++i) x.push_back(0.5 * (e[i] + e[i + 1]));
  return Grid(std::move(e), std::move(x));
}

Grid Grid::from_pivots(std::vector<double> x) {
  const size_t n = x.size();
  if (n < size_t(kMinClasses))
    throw ConfigError(violation("grid classes", double(n), "", "classes >= " + std::to_string(kMinClasses)));
  for (size_t i = 0; i < n; ++i)
    if (!(x[i] > 0) || (i > 0 && !(x[i] > x[i - 1])))
      throw ConfigError(violation("grid pivot " + std::to_string(i), x[i], "m3", "positive and increasing"));
  std::vector<double> e(n + 1);
  for (size_t i = 1; i < n; ++i) e[i] = std::sqrt(x[i - 1] * x[i]);
  e[0] = x[0] * x[0] / e[1];
  e[n] = x[n - 1] * x[n - 1] / e[n - 1];
  return Grid(std::move(e), std::move(x));
}

Grid Grid::from_diameter_pivots(const std::vector<double>& d) {
  std::vector<double> x;
  for (double di : d) x.push_back(volume_of_diameter(di));
  return from_pivots(std::move(x));
}

int Grid::cell_of(double v) const {
  if (v < edges_.front()) return -1;
  if (v >= edges_.back()) return size();
  return static_cast<int>(std::upper_bound(edges_.begin(), edges_.end(), v) - edges_.begin()) - 1;
}

int Grid::interval_of(double v) const {
  if (v < x_lo_) return -2;
  if (v >= x_hi_) return size();
  if (v < pivots_.front()) return -1;
  return static_cast<int>(std::upper_bound(pivots_.begin(), pivots_.end(), v) - pivots_.begin()) - 1;
}

}  // namespace granuflow::kernels
