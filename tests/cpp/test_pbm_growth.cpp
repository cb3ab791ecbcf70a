// Growth (layering) on the size grid: size-independent growth shifts the distribution in diameter without
// changing its shape (docs/verification.md), the limited scheme converges and keeps N >= 0, and the volume-normalized
// laws of paper 003 (Eqs. (7.33), (7.35)-(7.36)) deliver exactly the sprayed solids to the particles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "kernels/discretization/fv_growth.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"

namespace granuflow {
namespace {

namespace an = pbm_analytic;

// v from 2^-12 to 2^7 (d up to 5.9): room for the shift of 1 of a distribution with mean diameter 1.1.
constexpr int kDoublings = 19;

pbm_test::Run grow(const std::string& scheme, int q, double t_end) {
  auto s = pbm_test::grid_settings(q, kDoublings);
  s["growth"] = "constant";
  s["growth_scheme"] = scheme;
  auto fs = pbm_test::flowsheet(s, {{"growth_G", 1.0}});
  return pbm_test::run(*fs, {0, t_end}, 1e-8, 1e-12);
}

TEST(PbmGrowth, SizeIndependentGrowthShiftsTheDistribution) {
  const double shift = 1.0;  // G t, m
  std::vector<double> koren, upwind;
  for (int q : {4, 8, 16}) {
    const auto g = pbm_test::grid(q, kDoublings);
    const auto exact = an::growth_cell_volumes(g, shift);
    const auto rk = grow("fv_koren", q, shift), ru = grow("fv_upwind", q, shift);
    koren.push_back(an::l1_mass_error(g, rk.N(1), exact));
    upwind.push_back(an::l1_mass_error(g, ru.N(1), exact));
    // Number: conserved by the fluxes (nothing reaches the top edge at d = 5.9).
    EXPECT_NEAR(pbm_test::moment(g, rk.N(1), 0) / pbm_test::moment(g, rk.N(0), 0), 1.0, 1e-10);
    // Shape: the second volume moment of the shifted distribution (M2 = 6 at t = 0 grows to ~280).
    // Measured: -1.9e-2, -1.0e-2, -2.5e-3 (upwind: +0.45, +0.20, +0.09).
    EXPECT_NEAR(pbm_test::moment(g, rk.N(1), 2) / an::growth_moment(2, shift), 1.0, 0.03 / std::sqrt(q / 4.0)) << q;
    // No negative numbers from the limited scheme.
    const double nmax = *std::max_element(rk.N(1), rk.N(1) + g.size());
    for (int i = 0; i < g.size(); ++i) EXPECT_GT(rk.N(1)[i], -1e-10 * nmax) << "class " << i;
    // Book-keeping: volume on the grid + outside - created = initial volume, to round-off.
    const double v0 = pbm_test::moment(g, rk.N(0), 1);
    const double v = pbm_test::moment(g, rk.N(1), 1) + rk.state(1, "volume_above") + rk.state(1, "volume_below");
    EXPECT_NEAR((v - rk.state(1, "volume_grown")) / v0, 1.0, 1e-12);
  }
  // Measured L1 of the mass density (koren / upwind): q=4 0.0213/0.300, q=8 0.00408/0.159, q=16 0.00080/0.082:
  // order 2.4 for the limited kappa = 1/3 scheme (third order where smooth, second at the distribution's peak, where
  // the limiter acts), first order upwind. The kappa = -1/3 slope (a + 2b)/3 gave 0.059, 0.017, 0.0044 (order 1.9).
  for (size_t k = 0; k < koren.size(); ++k) EXPECT_LT(koren[k], 0.1 * upwind[k]) << "little numerical diffusion";
  EXPECT_LT(koren[1], 0.006);  // the kappa = -1/3 slope: 0.017
  for (size_t k = 1; k < koren.size(); ++k) {
    EXPECT_GT(std::log2(koren[k - 1] / koren[k]), 2.2) << koren[k - 1] << " -> " << koren[k];
    EXPECT_GT(std::log2(upwind[k - 1] / upwind[k]), 0.7) << upwind[k - 1] << " -> " << upwind[k];
  }
}

// Paper 003, Eq. (7.33) and Eqs. (7.35)-(7.36): the population gains exactly M_sus / rho_s m^3 per second.
TEST(PbmGrowth, MassGrowthRateIsExactForTheNormalizedLaws) {
  const double m_dot = 2e-3, rho_s = 1500.0;  // kg/s, kg/m3
  for (const char* law : {"surface_proportional", "moment_based"}) {
    pbm_test::Strings s{
        {"grid", "log_diameter"}, {"classes", "20"}, {"d_max", "3e-3"}, {"growth", law}, {"initial", "lognormal_mass"}};
    pbm_test::Values p{
        {"rho", rho_s}, {"mass0", 4.0}, {"d50_0", 300e-6}, {"growth_m_dot", m_dot}, {"growth_rho_s", rho_s}};
    if (std::string(law) == "moment_based") p["growth_lambda_2"] = 0.0, p["growth_lambda_3"] = 1.0;
    auto fs = pbm_test::flowsheet(s, p);
    const auto r = pbm_test::run(*fs, {0, 100, 600}, 1e-8, 1e-3);
    auto out = [&](size_t k, const std::string& name) { return r.output(k, name); };
    for (size_t k = 1; k < 3; ++k) {
      const double t = r.result.t[k];
      EXPECT_NEAR(out(k, "mass_grown") / (m_dot * t), 1.0, 1e-10) << law;
      EXPECT_NEAR((out(k, "mass") + out(k, "mass_above") - out(0, "mass")) / (m_dot * t), 1.0, 1e-9) << law;
      EXPECT_NEAR(out(k, "mass_balance"), 0.0, 1e-12) << law;
    }
    EXPECT_GT(out(2, "d50"), out(0, "d50"));
  }
}

}  // namespace
}  // namespace granuflow

namespace granuflow {
namespace {

// Pivot diameters from 0.1 mm over a factor 40, evenly spaced in log d.
kernels::Grid diameter_grid(size_t classes) {
  std::vector<double> d(classes);
  for (size_t i = 0; i < classes; ++i) d[i] = 1e-4 * std::pow(40.0, double(i) / (classes - 1));
  return kernels::Grid::from_diameter_pivots(d);
}

// The residual's path for doubles and a volume-normalized law (FvGrowth::flux_values: the interior faces' densities
// in one vector loop) against the scheme written out here operation by operation (fv_growth.hpp: upwind donor, van
// Albada's slope a b (a + b) / (a^2 + b^2) on the density jumps scaled to the donor's width, nothing through the bottom
// face, first order next to the ends; G_f = sum_k a_k s_k(d_f) / I_k with I_k = sum_f s_k(d_f) phi_f dx_f): the same
// fluxes, donors and volume rate to the bit, for a ragged distribution with empty classes, a flat stretch (the
// slope's q = 0 case) and two growth terms, one without solids to deliver. The Jets' path (the same template) agrees
// to round-off (a Jet divides by multiplying with the inverse).
TEST(PbmGrowth, NormalizedFluxesOfDoublesFollowTheSchemeBitForBit) {
  const kernels::Grid grid = diameter_grid(23);
  const int n = grid.size(), nf = n + 1;
  const auto& de = grid.diameter_edges();
  std::vector<double> N(n);
  for (int i = 0; i < n; ++i) N[i] = i % 7 == 3 ? 0.0 : i >= 10 && i <= 13 ? 2.5e6 : 1e6 * (1.3 + std::sin(1.7 * i));
  std::vector<double> shape(2 * size_t(nf)), amount = {3e-9, 0.0};
  for (int f = 0; f < nf; ++f) shape[f] = de[f] * de[f], shape[nf + f] = 1.0;
  for (bool limited : {true, false}) {
    kernels::FvGrowth fv(limited ? kernels::Limiter::kVanAlbada : kernels::Limiter::kNone);
    fv.setup(grid);
    const auto& dx = fv.face_volume_steps();
    kernels::GrowthTerms<double> g{2, shape.data(), amount.data(), true};
    std::vector<double> F(nf);
    std::vector<int> donor(nf);
    const double W = fv.fluxes(N.data(), g, F.data(), donor.data());
    // the scheme, written out
    std::vector<double> w(n), centre(n), rho(n), phi(nf, 0.0), want(nf);
    for (int i = 0; i < n; ++i) w[i] = de[i + 1] - de[i], centre[i] = 0.5 * (de[i] + de[i + 1]), rho[i] = N[i] / w[i];
    for (int f = 1; f < nf; ++f) {
      const int k = f - 1;
      phi[f] = rho[k];
      if (!limited || f == 1 || f == n) continue;
      const double a = (rho[k + 1] - rho[k]) * (w[k] / (centre[k + 1] - centre[k]));
      const double b = (rho[k] - rho[k - 1]) * (w[k] / (centre[k] - centre[k - 1]));
      phi[f] += 0.5 * (a * a + b * b > 0.0 ? a * b * (a + b) / (a * a + b * b) : 0.0);
    }
    double integral = 0.0;
    for (int f = 0; f < nf; ++f) integral += shape[f] * phi[f] * dx[f];
    const double scale = amount[0] * (1.0 / integral);  // the second term has no particles' surface to go to
    double want_W = 0.0;
    for (int f = 0; f < nf; ++f) want[f] = (0.0 + scale * shape[f]) * phi[f], want_W += want[f] * dx[f];
    EXPECT_EQ(W, want_W);
    EXPECT_NEAR(W, amount[0], 1e-15 * amount[0]);  // Eq. (7.33): the sprayed volume, to round-off
    for (int f = 0; f < nf; ++f) {
      EXPECT_EQ(F[f], want[f]) << f;
      EXPECT_EQ(donor[f], f - 1) << f;
    }
    std::vector<Jet> Nj(n), shape_j(shape.size()), amount_j(amount.size()), Fj(nf);
    for (int i = 0; i < n; ++i) Nj[i] = Jet(N[i]);
    for (size_t k = 0; k < shape.size(); ++k) shape_j[k] = Jet(shape[k]);
    for (size_t k = 0; k < amount.size(); ++k) amount_j[k] = Jet(amount[k]);
    const Jet Wj = fv.fluxes(Nj.data(), kernels::GrowthTerms<Jet>{2, shape_j.data(), amount_j.data(), true}, Fj.data(),
                             donor.data());
    EXPECT_NEAR(Wj.a, W, 1e-14 * std::abs(W));
    for (int f = 0; f < nf; ++f) EXPECT_NEAR(Fj[f].a, F[f], 1e-13 * std::abs(F[f])) << f;
  }
}

// The far tail of a narrow distribution on a wide grid holds densities of 1e-100 and less. The limited scheme's
// fluxes are homogeneous of degree 1 in N and its Jacobian of degree 0, so scaling the distribution by c scales the
// fluxes by c and leaves the Jacobian as it is, down to densities near the smallest double. Before, van Albada's
// derivatives divided q^2 = (a^2 + b^2)^2, which underflows below jumps of about 1e-77: 0 / 0, a NaN Jacobian, and
// a run on such a grid stopped at t = 0. Both limiters, doubles and Jets.
TEST(PbmGrowth, LimitedFluxesAndJacobianScaleWithTheDistributionDownToItsFarTail) {
  const kernels::Grid grid = diameter_grid(30);
  const int n = grid.size(), nf = n + 1;
  const auto& de = grid.diameter_edges();
  std::vector<double> N(n);
  for (int i = 0; i < n; ++i) N[i] = i % 7 == 3 ? 0.0 : 1e6 * (1.3 + std::sin(1.7 * i)) * std::exp(-0.05 * i * i);
  std::vector<double> shape(nf), amount = {3e-9};
  for (int f = 0; f < nf; ++f) shape[f] = de[f] * de[f];
  const kernels::GrowthTerms<double> g{1, shape.data(), amount.data(), false};
  for (auto limiter : {kernels::Limiter::kVanAlbada, kernels::Limiter::kKoren}) {
    kernels::FvGrowth fv(limiter);
    fv.setup(grid);
    std::vector<double> F0(nf), J0(size_t(nf) * n);
    std::vector<int> donor(nf);
    fv.fluxes(N.data(), g, F0.data(), donor.data());
    fv.flux_jacobian(N.data(), g, J0.data());
    double jmax = 0.0, fmax = 0.0;
    for (double v : J0) jmax = std::max(jmax, std::abs(v));
    for (double v : F0) fmax = std::max(fmax, std::abs(v));
    ASSERT_GT(jmax, 0.0);
    for (double c : {1e-60, 1e-100, 1e-140, 1e-200}) {
      std::vector<double> Nc(n), F(nf), J(size_t(nf) * n);
      for (int i = 0; i < n; ++i) Nc[i] = c * N[i];
      fv.fluxes(Nc.data(), g, F.data(), donor.data());
      fv.flux_jacobian(Nc.data(), g, J.data());
      for (size_t k = 0; k < J.size(); ++k) {
        ASSERT_TRUE(std::isfinite(J[k])) << "c " << c << " entry " << k;
        EXPECT_NEAR(J[k], J0[k], 1e-12 * jmax) << "c " << c << " entry " << k;
      }
      for (int f = 0; f < nf; ++f) EXPECT_NEAR(F[f] / c, F0[f], 1e-12 * fmax) << "c " << c << " face " << f;
      std::vector<Jet> Nj(n), shape_j(shape.begin(), shape.end()), amount_j(amount.begin(), amount.end()), Fj(nf);
      for (int i = 0; i < n; ++i) Nj[i] = Jet(Nc[i]), Nj[i].v[0] = Nc[i];  // d/ds of N (1 + s): the fluxes again
      fv.fluxes(Nj.data(), kernels::GrowthTerms<Jet>{1, shape_j.data(), amount_j.data(), false}, Fj.data(),
                donor.data());
      for (int f = 0; f < nf; ++f) {
        ASSERT_TRUE(std::isfinite(Fj[f].a) && std::isfinite(Fj[f].v[0])) << "c " << c << " face " << f;
        EXPECT_NEAR(Fj[f].v[0] / c, F0[f], 1e-12 * fmax) << "c " << c << " face " << f;
      }
    }
  }
}

}  // namespace
}  // namespace granuflow
