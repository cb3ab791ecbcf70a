// Helpers shared by the scene-level tests: load scenes from text or from flowsheets/, look up reported outputs by
// name, and compare the assembled Jacobian with central finite differences of the residual.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "granuflow/dae_system.hpp"
#include "granuflow/scene.hpp"
#include "granuflow/simulator.hpp"
#include "units/registry.hpp"

namespace granuflow::testing {

inline std::string repo_path(const std::string& rel) { return std::string(GRANUFLOW_SOURCE_DIR) + "/" + rel; }

inline Scene scene_from_text(const std::string& yaml) { return load_scene_text(yaml, "<test>", units::builtin()); }
inline Scene scene_from_file(const std::string& rel) { return load_scene(repo_path(rel), units::builtin()); }

// Column `c` of dF/dy + cj dF/dy' at (y, yp) by a central difference with step h (y' moves with cj h, as the
// integrator's Newton matrix does); `fd` receives n values, `r0`, `r1` are scratch of size n.
inline void central_difference_column(DaeSystem& sys, double t, const std::vector<double>& y,
                                      const std::vector<double>& yp, double cj, int c, double h,
                                      std::vector<double>& fd, std::vector<double>& r0, std::vector<double>& r1) {
  const size_t n = y.size();
  fd.resize(n), r0.resize(n), r1.resize(n);
  auto yy = y, yyp = yp;
  yy[c] += h, yyp[c] += cj * h;
  sys.residual(t, yy.data(), yyp.data(), r1.data());
  yy[c] -= 2 * h, yyp[c] -= 2 * cj * h;
  sys.residual(t, yy.data(), yyp.data(), r0.data());
  for (size_t r = 0; r < n; ++r) fd[r] = (r1[r] - r0[r]) / (2 * h);
}

// Every entry of dF/dy + cj dF/dy' at (y, yp) against central differences; `rel` relative to the column's
// largest entry, so entries that are round-off of large neighbours do not fail the check.
inline void expect_jacobian_matches_fd(DaeSystem& sys, double t, const std::vector<double>& y,
                                       const std::vector<double>& yp, double cj, double rel) {
  const int n = sys.size();
  std::vector<double> jac(size_t(n) * n), fd, r0, r1;
  sys.jacobian(t, y.data(), yp.data(), cj, jac.data(), nullptr);
  const auto scale = sys.scales();
  for (int c = 0; c < n; ++c) {
    central_difference_column(sys, t, y, yp, cj, c, 1e-6 * std::max(std::abs(y[c]), scale[c]), fd, r0, r1);
    double colmax = 0;
    for (int r = 0; r < n; ++r) colmax = std::max(colmax, std::abs(jac[size_t(c) * n + r]));
    for (int r = 0; r < n; ++r) {
      EXPECT_NEAR(jac[size_t(c) * n + r], fd[r], rel * std::max(colmax, std::abs(fd[r])) + 1e-14)
          << "d(" << sys.describe_row(r) << ") / d(" << sys.flowsheet().state_names()[c] << ")";
    }
  }
}

// The structured Jacobian (analytic parts, coloured AD, reductions) against plain forward AD of every unit
// (DaeSystem::reference_jacobian), relative to each column's largest entry. `sys` must not inline explicit units.
inline void expect_jacobian_matches_reference(DaeSystem& sys, double t, const std::vector<double>& y,
                                              const std::vector<double>& yp, double cj, double rel) {
  const int n = sys.size();
  std::vector<double> jac(size_t(n) * n), ref(size_t(n) * n);
  sys.jacobian(t, y.data(), yp.data(), cj, jac.data(), nullptr);
  sys.reference_jacobian(t, y.data(), yp.data(), cj, ref.data());
  for (int c = 0; c < n; ++c) {
    double colmax = 0;
    for (int r = 0; r < n; ++r) colmax = std::max(colmax, std::abs(ref[size_t(c) * n + r]));
    for (int r = 0; r < n; ++r)
      EXPECT_NEAR(jac[size_t(c) * n + r], ref[size_t(c) * n + r], rel * colmax + 1e-300)
          << "d(" << sys.describe_row(r) << ") / d(" << sys.flowsheet().state_names()[c] << ")";
  }
}

// Column of the reported output `name` (a failure, not a silent 0, when the run does not report it).
inline int output_index(const SimResult& r, const std::string& name) {
  for (size_t i = 0; i < r.output_names.size(); ++i)
    if (r.output_names[i] == name) return static_cast<int>(i);
  ADD_FAILURE() << "no output " << name;
  return 0;
}
inline double output(const SimResult& r, size_t k, const std::string& name) {
  return r.outputs[k * r.output_names.size() + output_index(r, name)];
}

}  // namespace granuflow::testing
