// Breakage on the grid: Ziff & McGrady's binary breakage (b = 2/u, S = v) against its analytic solution, volume
// conservation of the breakage matrix for every fragment law and scheme, and paper 001's laws in a batch.
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/discretization/breakage_scheme.hpp"
#include "kernels/registry.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"

namespace granuflow {
namespace {

namespace an = pbm_analytic;

TEST(PbmBreakage, MatrixColumnsConserveVolumeForEveryLawAndScheme) {
  const auto g = kernels::Grid::geometric(1e-13, 2, 20);
  auto& reg = kernels::registries();
  for (const auto& scheme : reg.breakage_schemes.names())
    for (const auto& law : reg.fragments.names()) {
      const auto b = reg.breakage_schemes.create(scheme);
      const auto f = reg.fragments.create(law);
      std::vector<double> p;
      for (const auto& s : f->params()) p.push_back(s.value);
      const int n = g.size();
      std::vector<double> A(size_t(n + kernels::kOutsideRows) * n);
      b->build(g, *f, p.data(), A.data());
      for (int k = 0; k < n; ++k) {
        double dv = A[size_t(n + kernels::kVolumeBelow) * n + k];
        for (int i = 0; i < n; ++i) {
          dv += A[size_t(i) * n + k] * g.pivot(i);
          if (i > k) {
            EXPECT_EQ(A[size_t(i) * n + k], 0.0) << "fragment above its parent";
          }
          if (i != k) {
            EXPECT_GE(A[size_t(i) * n + k], 0.0) << scheme << " " << law;
          }
        }
        EXPECT_NEAR(dv / g.pivot(k), 0.0, 1e-14) << scheme << " " << law << " parent " << k;
      }
    }
}

TEST(PbmBreakage, BinaryBreakageMatchesZiffMcGrady) {
  for (const char* scheme : {"cell_average", "fixed_pivot"}) {
    auto s = pbm_test::grid_settings(4);
    s["breakage"] = "linear";
    s["fragments"] = "uniform_binary";
    s["breakage_scheme"] = scheme;
    auto fs = pbm_test::flowsheet(s);
    const auto g = pbm_test::grid(4);
    const auto r = pbm_test::run(*fs, {0, 1, 3, 10});
    const double v0 = pbm_test::moment(g, r.N(0), 1);
    for (size_t k = 1; k < r.result.t.size(); ++k) {
      const double t = r.result.t[k];
      // Number: each event adds one particle and both schemes keep number and volume of every fragment
      // packet, so the number on the grid follows the analytic number above e_0 (fragments below the grid
      // leave it: 0.27 % of the particles at t = 10).
      const double on_grid = an::ziff_m0(t) * std::exp(-(1.0 + t) * g.edge(0));
      EXPECT_NEAR(pbm_test::moment(g, r.N(k), 0) / on_grid, 1.0, 2e-4) << scheme << " t = " << t;
      EXPECT_NEAR(pbm_test::moment(g, r.N(k), 2) / an::ziff_m2(t), 1.0, 1e-2) << scheme << " t = " << t;
      const auto exact = an::cell_volumes(g, [&](double v) { return an::ziff_density(v, t); });
      EXPECT_LT(an::l1_mass_error(g, r.N(k), exact), 0.02) << scheme << " t = " << t;
      // Volume book-keeping: on the grid plus below the grid, to round-off.
      EXPECT_NEAR((pbm_test::moment(g, r.N(k), 1) + r.state(k, "volume_below")) / v0, 1.0, 1e-12);
    }
  }
}

TEST(PbmBreakage, PaperOneLawsConserveMassWithFinesFolded) {
  // Paper 001: Vogel-Peukert rate (Eq. (92)) and tanh power-law fragments (Eq. (93)); fines below the first
  // class stay in it with their mass (docs/paper001_decisions.md).
  pbm_test::Strings s{{"grid", "log_diameter"},        {"classes", "10"},   {"breakage", "vogel_peukert"},
                      {"fragments", "tanh_power_law"}, {"outside", "fold"}, {"initial", "lognormal_mass"}};
  auto fs = pbm_test::flowsheet(s, {{"rho", 1081.5}, {"mass0", 15.0}, {"d50_0", 400e-6}, {"sel_k_break", 1e-2}});
  const auto r = pbm_test::run(*fs, {0, 60, 600}, 1e-8, 1e-6);
  auto out = [&](size_t k, const std::string& name) { return r.output(k, name); };
  EXPECT_NEAR(out(0, "mass"), 15.0, 0.5);  // the grid (50-1000 um pivots) holds nearly all of d50 = 400 um
  for (size_t k = 1; k < 3; ++k) {
    EXPECT_NEAR(out(k, "mass") / out(0, "mass"), 1.0, 1e-12);
    EXPECT_NEAR(out(k, "mass_balance"), 0.0, 1e-12);
  }
  EXPECT_LT(out(2, "d50"), out(0, "d50"));  // breakage makes the particles smaller
  EXPECT_GT(out(2, "number"), out(0, "number"));
}

}  // namespace
}  // namespace granuflow
