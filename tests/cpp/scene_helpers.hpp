// Helpers shared by the scene-level tests: load scenes from text or from flowsheets/, and compare the assembled
// Jacobian with central finite differences of the residual.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "granuflow/dae_system.hpp"
#include "granuflow/scene.hpp"
#include "units/registry.hpp"

namespace granuflow::testing {

inline std::string repo_path(const std::string& rel) { return std::string(GRANUFLOW_SOURCE_DIR) + "/" + rel; }

inline Scene scene_from_text(const std::string& yaml) { return load_scene_text(yaml, "<test>", units::builtin()); }
inline Scene scene_from_file(const std::string& rel) { return load_scene(repo_path(rel), units::builtin()); }

// Every entry of dF/dy + cj dF/dy' at (y, yp) against central differences; `rel` relative to the column's
// largest entry, so entries that are round-off of large neighbours do not fail the check.
inline void expect_jacobian_matches_fd(DaeSystem& sys, double t, const std::vector<double>& y,
                                       const std::vector<double>& yp, double cj, double rel) {
  const int n = sys.size();
  std::vector<double> jac(size_t(n) * n), r0(n), r1(n);
  sys.jacobian(t, y.data(), yp.data(), cj, jac.data(), nullptr);
  const auto scale = sys.scales();
  for (int c = 0; c < n; ++c) {
    const double h = 1e-6 * std::max(std::abs(y[c]), scale[c]);
    auto yy = y, yyp = yp;
    yy[c] += h, yyp[c] += cj * h;
    sys.residual(t, yy.data(), yyp.data(), r1.data());
    yy[c] -= 2 * h, yyp[c] -= 2 * cj * h;
    sys.residual(t, yy.data(), yyp.data(), r0.data());
    double colmax = 0;
    for (int r = 0; r < n; ++r) colmax = std::max(colmax, std::abs(jac[size_t(c) * n + r]));
    for (int r = 0; r < n; ++r) {
      const double fd = (r1[r] - r0[r]) / (2 * h);
      EXPECT_NEAR(jac[size_t(c) * n + r], fd, rel * std::max(colmax, std::abs(fd)) + 1e-14)
          << "d(" << sys.describe_row(r) << ") / d(" << sys.flowsheet().state_names()[c] << ")";
    }
  }
}

}  // namespace granuflow::testing
