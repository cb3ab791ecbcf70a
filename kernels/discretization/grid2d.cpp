#include "discretization/grid2d.hpp"

#include <cmath>
#include <string>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

Grid2D::Grid2D(std::shared_ptr<const Grid> solid, int liquid_classes, double liquid_step)
    : solid_(std::move(solid)), nl_(liquid_classes), dl_(liquid_step) {
  if (nl_ < 2) throw ConfigError(violation("liquid classes", nl_, "", "liquid classes >= 2"));
  if (!(dl_ > 0) || !std::isfinite(dl_)) throw ConfigError(violation("liquid step", dl_, "m3", "liquid step > 0"));
  const int n = size();
  volume_.resize(n), diameter_.resize(n), content_.resize(n);
  for (int a = 0; a < n; ++a) {
    volume_[a] = total_volume(a);
    diameter_[a] = diameter_of_volume(volume_[a]);
    content_[a] = liquid_volume(a) / volume_[a];
  }
}

Grid2D::LiquidSplit Grid2D::shift(int j, double dv) const {
  const double x = j + dv / dl_;  // new liquid volume in steps
  if (x <= 0) return {0, 0, 1.0, 0.0};
  const double f = std::floor(x);
  const int lo = static_cast<int>(f);
  const double nu = x - f;  // keeps sum w = 1 and sum w index = x
  return {lo, lo + 1, 1.0 - nu, nu};
}

}  // namespace granuflow::kernels
