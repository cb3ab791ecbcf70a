// The review's drying closures (paper 000, sections 5.2 and 5.4.1; kernels/drying/): each normalized drying curve
// and each drying surface at its limits, the cubic's rule refused with one line, and a scene that names them.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "kernels/drying/drying_curves.hpp"
#include "kernels/drying/drying_surfaces.hpp"
#include "kernels/registry.hpp"
#include "kernels/wetting/spray_filtration.hpp"
#include "kernels/wetting/stokes_deformation.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using kernels::registries;

std::vector<double> curve(const std::string& name, const std::vector<double>& eta, std::vector<double> p) {
  auto k = registries().drying_curves.create(name);
  std::vector<double> v(eta.size());
  k->apply(eta.data(), static_cast<int>(eta.size()), p.data(), v.data());
  return v;
}

const std::vector<double> kEta = {-0.2, 0.0, 0.05, 0.3, 0.5, 0.77, 0.999, 1.0, 1.7};

TEST(DryingCurves, GammaOneAndCubicAOneAreTheLinearCurve) {
  const auto lin = curve("linear", kEta, {});
  const auto g1 = curve("gamma", kEta, {1.0});
  const auto c1 = curve("cubic", kEta, {1.0, 0.0, 0.0});
  for (size_t i = 0; i < kEta.size(); ++i) {
    EXPECT_DOUBLE_EQ(lin[i], std::min(kEta[i], 1.0));
    EXPECT_DOUBLE_EQ(g1[i], lin[i]) << kEta[i];
    EXPECT_DOUBLE_EQ(c1[i], lin[i]) << kEta[i];
  }
}

TEST(DryingCurves, EveryCurveStartsAtZeroMeetsOneAndStaysThere) {
  const std::vector<std::pair<std::string, std::vector<double>>> cases = {
      {"linear", {}}, {"gamma", {0.3}}, {"gamma", {4.0}}, {"cubic", {0.2, 1.5, -0.7}}};
  for (const auto& [name, p] : cases) {
    const auto v = curve(name, {0.0, 1.0, 1.0 + 1e-9, 3.0}, p);
    EXPECT_EQ(v[0], 0.0) << name;
    EXPECT_NEAR(v[1], 1.0, 1e-15) << name;
    EXPECT_EQ(v[2], 1.0) << name;  // constant-rate period
    EXPECT_EQ(v[3], 1.0) << name;
  }
}

// Below equilibrium each curve is its tangent at 0: finite and monotone where gamma's printed form has a pole.
TEST(DryingCurves, BelowEquilibriumTheTangentAtZero) {
  EXPECT_DOUBLE_EQ(curve("gamma", {-0.5}, {3.0})[0], -1.5);  // the printed form: 3 (-0.5) / (1 - 1) diverges
  EXPECT_DOUBLE_EQ(curve("gamma", {-0.2}, {0.3})[0], -0.06);
  EXPECT_DOUBLE_EQ(curve("cubic", {-0.4}, {0.5, 0.3, 0.2})[0], -0.2);
}

TEST(DryingCurves, GammaAboveOneDriesFasterBelowOneSlower) {
  for (double eta : {0.1, 0.4, 0.8}) {
    const double fast = curve("gamma", {eta}, {3.0})[0], slow = curve("gamma", {eta}, {0.3})[0];
    EXPECT_GT(fast, eta);
    EXPECT_LT(slow, eta);
    EXPECT_NEAR(fast, 3.0 * eta / (1.0 + 2.0 * eta), 1e-15);  // paper 000, section 5.4.1
  }
}

TEST(DryingCurves, GammaDerivativeIsTheClosedForm) {
  auto k = registries().drying_curves.create("gamma");
  const double g = 2.5, eta = 0.35;
  Jet e(eta), p(g);
  p.v[0] = 1.0;
  Jet v;
  k->apply(&e, 1, &p, &v);
  const double den = 1.0 + (g - 1.0) * eta;
  EXPECT_NEAR(v.v[0], eta * (1.0 - eta) / (den * den), 1e-15);  // d/dgamma of gamma X / (1 + (gamma - 1) X)
}

TEST(DryingCurves, CubicRefusesCoefficientsNotSummingToOne) {
  auto k = registries().drying_curves.create("cubic");
  const double ok[] = {0.5, 0.3, 0.2}, bad[] = {0.5, 0.3, 0.3};
  EXPECT_NO_THROW(k->check({}, ok, "bed"));
  try {
    k->check({}, bad, "bed");
    FAIL() << "A + B + C = 1.1 accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("A + B + C = 1.1"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

double wet(const std::string& name, double area, double liquid, std::vector<double> p) {
  auto k = registries().drying_surfaces.create(name);
  double w = 0.0;
  k->apply(&area, &liquid, 1, p.data(), &w);
  return w;
}

TEST(DryingSurfaces, FilmAndCorrection) {
  EXPECT_EQ(wet("film", 2.0, 0.3, {}), 2.0);
  EXPECT_EQ(wet("correction", 2.0, 0.3, {1.0}), 2.0);
  EXPECT_DOUBLE_EQ(wet("correction", 2.0, 0.3, {0.25}), 0.5);
}

TEST(DryingSurfaces, CoverageLimits) {
  const double d = 30e-6, rho = 1000.0, area = 3.0;
  // little liquid: the droplets' projected areas without overlap, n_d pi d^2 / 4 = 3 V / (2 d)
  const double m = 1e-12;
  EXPECT_NEAR(wet("coverage", area, m, {d, rho}), 1.5 * (m / rho) / d, 1e-9 * 1.5 * (m / rho) / d);
  // much liquid: the whole surface, never more
  EXPECT_NEAR(wet("coverage", area, 10.0, {d, rho}), area, 1e-12);
  EXPECT_LE(wet("coverage", area, 10.0, {d, rho}), area);
  // an emptied class: no area, no liquid, no wetted area (not 0 / 0)
  EXPECT_EQ(wet("coverage", 0.0, 0.0, {d, rho}), 0.0);
  EXPECT_EQ(wet("droplet_height", 0.0, 0.0, {d, rho, 1.0}), 0.0);
}

TEST(DryingSurfaces, DropletHeightCapsAtTheirContactAngle) {
  const double d = 30e-6, rho = 1000.0, area = 3.0, pi = kernels::kPi;
  // hemispheres (theta = pi / 2): a = h = (3 V / (2 pi))^(1/3); little liquid dries over n_d 2 pi a^2
  const double v = pi / 6.0 * d * d * d, a = std::cbrt(3.0 * v / (2.0 * pi)), m = 1e-12;
  const double n_d = m / rho / v;
  EXPECT_NEAR(wet("droplet_height", area, m, {d, rho, pi / 2.0}), n_d * 2.0 * pi * a * a, 1e-8 * n_d * a * a);
  // a covered surface of hemispheres has twice the surface as interface
  EXPECT_NEAR(wet("droplet_height", area, 10.0, {d, rho, pi / 2.0}), 2.0 * area, 1e-12);
  // flat caps (small angle): the interface is the footprint, the coverage of a larger footprint
  const double flat = wet("droplet_height", area, 10.0, {d, rho, 0.01});
  EXPECT_NEAR(flat, area, 1e-4 * area);
  // Eq. (7.53) with Eq. (7.54) gives back the cap's volume pi h (3 a^2 + h^2) / 6
  const double th = 0.7, ac = kernels::cap_base_radius(v, th), h = ac * kernels::cap_aspect(th);
  EXPECT_NEAR(pi * h * (3.0 * ac * ac + h * h) / 6.0, v, 1e-12 * v);
}

// The fluid bed names its closures; a cubic that violates A + B + C = 1 is refused before the run, in one line.
TEST(DryingClosuresScene, FluidBedRefusesABadCubic) {
  const std::string yaml = R"(
scene: bad_cubic
t_end: 1 min
particles: {material: maltodextrin_de21, settings: {classes: 6, d_min: 50e-6, d_max: 1000e-6}}
units:
  inlet: {type: gas_inlet, params: {V_dot: 700 m3/h, T: 60 degC, Y: 5 g/kg}}
  gas: {type: chamber_gas}
  bed: {type: fluid_bed, settings: {drying_curve: cubic}, params: {drying_A: 0.6, drying_B: 0.6, drying_C: 0.6}}
  exhaust: {type: gas_outlet}
connections: [inlet.out -> gas.in, inlet.state -> bed.inlet, gas.state -> bed.gas, bed.vapour -> gas.drying,
              gas.solids -> bed.heat, gas.out -> exhaust.in]
)";
  try {
    Scene bad = testing::scene_from_text(yaml);
    simulate(*bad.flowsheet, bad.options);
    FAIL() << "A + B + C = 1.8 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("A + B + C = 1.8"), std::string::npos) << e.what();
  }
}

// Spray filtration (paper 000, section 5.1.4): the Happel-type factor is 1 in a dilute bed, the collector efficiency
// runs from 0 (droplets follow the gas) to 1 (inertial droplets all caught) and is 1/2 at St*^3.2 = 4.3.
TEST(SprayFiltration, Limits) {
  namespace f = kernels::filtration;
  EXPECT_NEAR(f::happel_factor(1e-12), 1.0, 1e-3);
  EXPECT_GT(f::happel_factor(0.4), 1.0);  // a denser bed deflects the gas more
  EXPECT_NEAR(f::single_collector_efficiency(1e-4), 0.0, 1e-12);
  EXPECT_NEAR(f::single_collector_efficiency(1e4), 1.0, 1e-12);
  EXPECT_NEAR(f::single_collector_efficiency(std::pow(4.3, 1.0 / 3.2)), 0.5, 1e-14);
  // St grows with the droplet's size squared; Re_m with the slip
  const double st1 = f::droplet_stokes_number(1.0, 30e-6, 1000.0, 200e-6, 1.8e-5, 0.6);
  EXPECT_NEAR(f::droplet_stokes_number(1.0, 60e-6, 1000.0, 200e-6, 1.8e-5, 0.6), 4.0 * st1, 1e-12 * st1);
  EXPECT_NEAR(st1, 30e-6 * 30e-6 * 1000.0 / (18.0 * 200e-6 * 1.8e-5 * 0.6), 1e-12 * st1);
  const double lambda = f::filtration_coefficient(0.5, 0.4, 200e-6);
  EXPECT_NEAR(lambda, 0.5 * 1.5 * 0.4 / 200e-6, 1e-9);
  EXPECT_LT(f::deposition_rate(lambda, 1.0, 0.01, 0.6, 1.1), 0.0);  // a sink of the droplets
  EXPECT_NEAR(f::filtered_fraction(lambda, 1.0), 1.0, 1e-12);       // a deep bed catches every droplet
}

// Stokes deformation (paper 000, section 5.6): twice the critical coalescence number; a granule with a layer at the
// asperity height has none.
TEST(StokesDeformation, TwiceTheCriticalCoalescenceNumber) {
  namespace st = kernels::stokes;
  const double e = 0.5, h = 10e-6, ha = 1e-6;
  EXPECT_NEAR(st::critical_coalescence(e, h, ha), 3.0 * std::log(10.0), 1e-14);
  EXPECT_NEAR(st::critical_deformation(e, h, ha), 6.0 * std::log(10.0), 1e-14);
  EXPECT_EQ(st::critical_deformation(e, ha, ha), 0.0);
  // drying thins the layer: the critical number falls
  EXPECT_LT(st::critical_deformation(e, 5e-6, ha), st::critical_deformation(e, h, ha));
  EXPECT_NEAR(st::viscous_stokes_number(1.0, 3.0 * kernels::kPi, 2.0, 1.0), 1.0, 1e-15);
}

}  // namespace
}  // namespace granuflow
