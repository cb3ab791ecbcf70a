// The structured Jacobian of pbm_batch (the engine's analytic part, coloured AD for the rest) against plain forward
// AD of the whole residual (DaeSystem::reference_jacobian) and central finite
// differences, for every scheme and mechanism, on random positive states.
#include <gtest/gtest.h>

#include <random>

#include "granuflow/dae_system.hpp"
#include "pbm_test_helpers.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using pbm_test::Strings;

void check_jacobian(const Strings& settings, const pbm_test::Values& params = {}) {
  auto fs = pbm_test::flowsheet(settings, params);
  DaeSystem sys(*fs);
  const int n = sys.size();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.2, 1.0);
  std::vector<double> y(n), yp(n), dense(size_t(n) * n), fd, r0, r1;
  sys.initial_values(y);
  for (int i = 0; i < n; ++i) y[i] = std::abs(y[i]) * u(rng) + 1e-3 * u(rng), yp[i] = 0.1 * u(rng);
  const double cj = 2.5;
  sys.jacobian(0.0, y.data(), yp.data(), cj, dense.data(), nullptr);
  std::vector<double> ad(size_t(n) * n);  // column-major, plain forward AD of the whole residual
  sys.reference_jacobian(0.0, y.data(), yp.data(), cj, ad.data());
  double scale = 0;
  for (double v : ad) scale = std::max(scale, std::abs(v));
  for (int c = 0; c < n; ++c) {
    testing::central_difference_column(sys, 0, y, yp, cj, c, 1e-6 * std::max(1e-3, std::abs(y[c])), fd, r0, r1);
    for (int row = 0; row < n; ++row) {
      const double an = dense[size_t(c) * n + row], a = ad[size_t(c) * n + row];
      ASSERT_NEAR(an, a, 1e-11 * scale) << "analytic vs AD, row " << row << " col " << c;
      ASSERT_NEAR(an, fd[row], 1e-6 * scale) << "analytic vs FD, row " << row << " col " << c;
    }
  }
}

Strings with(Strings s, const Strings& more) {
  for (const auto& [k, v] : more) s[k] = v;
  return s;
}

class PbmJacobian : public ::testing::TestWithParam<Strings> {};

TEST_P(PbmJacobian, AnalyticEqualsAdAndFiniteDifferences) {
  check_jacobian(with(pbm_test::grid_settings(2, 12), GetParam()));
}

INSTANTIATE_TEST_SUITE_P(
    Mechanisms, PbmJacobian,
    ::testing::Values(Strings{{"aggregation", "constant"}, {"aggregation_scheme", "cell_average"}},
                      Strings{{"aggregation", "sum"}, {"aggregation_scheme", "cell_average"}},
                      Strings{{"aggregation", "product"}, {"aggregation_scheme", "fixed_pivot"}},
                      Strings{{"aggregation", "sum"}, {"aggregation_scheme", "fixed_pivot"}, {"outside", "fold"}},
                      Strings{{"aggregation", "eke"}, {"aggregation_scheme", "cell_average"}},
                      Strings{{"breakage", "linear"}, {"breakage_scheme", "cell_average"}},
                      Strings{
                          {"breakage", "power_law"}, {"fragments", "power_law"}, {"breakage_scheme", "fixed_pivot"}},
                      Strings{{"breakage", "linear"}, {"fragments", "tanh_power_law"}, {"outside", "fold"}},
                      Strings{{"growth", "constant"}, {"growth_scheme", "fv_koren"}},
                      Strings{{"growth", "constant"}, {"growth_scheme", "fv_upwind"}},
                      Strings{{"growth", "surface_proportional"}},
                      Strings{{"growth", "moment_based"}, {"outside", "fold"}},
                      Strings{{"aggregation", "kapur"}, {"breakage", "linear"}, {"growth", "surface_proportional"}}));

TEST(PbmJacobianAll, PaperOneKernelsWithStateFromParameters) {
  check_jacobian(with(pbm_test::grid_settings(1, 12), {{"aggregation", "glass_transition"},
                                                       {"breakage", "vogel_peukert"},
                                                       {"fragments", "tanh_power_law"},
                                                       {"v_min", "1e-13"}}),
                 {{"wetted_fraction", 0.3}, {"X_spot", 0.2}, {"T", 330.0}});
}

TEST(PbmJacobianAll, NegativeGrowthUpwindsFromAbove) {
  check_jacobian(with(pbm_test::grid_settings(2, 12), {{"growth", "constant"}}), {{"growth_G", -0.05}});
}

}  // namespace
}  // namespace granuflow
