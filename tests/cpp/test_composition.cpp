// Particles of several solids (particles: components): per class the mass of each component, carried by layering,
// aggregation and breakage. Each component's balance closes, the cores' mass never changes, the layer gains exactly
// the sprayed solids, and the Jacobian (plain forward AD of the composed chamber) equals finite differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "granuflow/dae_system.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::output;
using testing::scene_from_text;

// Relative closure |dHold - (in - out)| / max(...) over every balance output of quantity q.
double closure(const Scene& s, const SimResult& r, const std::string& q) {
  double in = 0, out = 0, h0 = 0, h1 = 0;
  const size_t last = r.t.size() - 1;
  size_t i = 0;
  for (const auto& u : s.flowsheet->units())
    for (const auto& o : u.spec.outputs()) {
      const double a = r.outputs[i], b = r.outputs[last * r.output_names.size() + i];
      ++i;
      if (o.quantity != q) continue;
      if (o.role == OutputRole::kBalanceIn) in += b - a;
      if (o.role == OutputRole::kBalanceOut) out += b - a;
      if (o.role == OutputRole::kBalanceHold) h0 += a, h1 += b;
    }
  return std::abs(h1 - h0 - (in - out)) / std::max({std::abs(h0), std::abs(h1), std::abs(in), std::abs(out)});
}

// A batch bed of 1040 kg/m3 cores sprayed with a 1440 kg/m3 layer, aggregating and breaking at once (rates far above
// any real bed's, so that every mechanism moves much mass in 20 min); `mechanisms` the chamber's settings.
std::string scene(const std::string& mechanisms) {
  std::string rates;
  if (mechanisms.find("aggregation") != std::string::npos) rates += ", agg_beta0: 1e-10";
  if (mechanisms.find("breakage") != std::string::npos) rates += ", sel_s0: 2e-4, sel_v_ref: 1e-9";
  return R"(
scene: composed_batch
t_end: 20 min
output: {n: 5}
solver: {rtol: 1e-9, atol: 1e-11}
particles:
  settings: {classes: 14, d_min: 4.0e-4, d_max: 4.0e-3, components: "core, layer"}
  params: {rho_s: 1040, eps_intra: 0, rho_layer: 1440}
units:
  bed:
    type: granulator
    settings: {discharge: none, spray_component: layer, )" +
         mechanisms + R"(}
    params: {bed_mass: 4 kg, d50_0: 1.2 mm, sigma_0: 1.3, m_spray: 112 g/min, w_spray: 0.3)" +
         rates + R"(}
)";
}

const char* kAll = "aggregation: constant, aggregation_scheme: cell_average, breakage: linear";

TEST(Composition, EachComponentIsConservedUnderLayeringAggregationAndBreakage) {
  for (const char* mech : {kAll, "aggregation: constant, aggregation_scheme: fixed_pivot", "breakage: linear"}) {
    SCOPED_TRACE(mech);
    Scene s = scene_from_text(scene(mech));
    const SimResult r = simulate(*s.flowsheet, s.options);
    const size_t last = r.t.size() - 1;
    const double sprayed = 0.112 / 60 * 0.3 * r.t[last];
    EXPECT_LT(closure(s, r, "solids:core"), 1e-9);
    EXPECT_LT(closure(s, r, "solids:layer"), 1e-9);
    EXPECT_LT(closure(s, r, "solids"), 1e-9);
    EXPECT_NEAR(output(r, last, "bed.mass_core"), 4.0, 1e-8);  // the cores neither grow nor vanish
    EXPECT_NEAR(output(r, last, "bed.mass_layer"), sprayed, 1e-8 * sprayed);
    EXPECT_NEAR(output(r, last, "bed.mass"), 4.0 + sprayed, 1e-8);
    // every class holds a composition: no component below zero beyond round-off, the layer spread over the classes
    int layered = 0;
    for (int i = 0; i < 14; ++i) {
      const std::string k = std::to_string(i);
      EXPECT_GT(output(r, last, "bed.core_mass_" + k), -1e-10);
      EXPECT_GT(output(r, last, "bed.layer_mass_" + k), -1e-10);
      layered += output(r, last, "bed.layer_mass_" + k) > 1e-6;
    }
    EXPECT_GE(layered, 5);
    // the mechanisms are strong: the number of particles moves by more than 10 %
    EXPECT_GT(std::abs(output(r, last, "bed.particles") / output(r, 0, "bed.particles") - 1), 0.1);
  }
}

// Class numbers follow the composition (N_i = sum_c m_c,i / rho_c / x_i): layering at the layer's density keeps the
// number of particles, aggregation lowers it.
TEST(Composition, LayeringKeepsTheNumberOfParticlesAndAggregationLowersIt) {
  Scene a = scene_from_text(scene("growth_scheme: fv_van_albada"));
  const SimResult ra = simulate(*a.flowsheet, a.options);
  const size_t last = ra.t.size() - 1;
  EXPECT_NEAR(output(ra, last, "bed.particles") / output(ra, 0, "bed.particles"), 1.0, 1e-6);
  Scene b = scene_from_text(scene("aggregation: constant, aggregation_scheme: cell_average"));
  const SimResult rb = simulate(*b.flowsheet, b.options);
  EXPECT_LT(output(rb, last, "bed.particles"), 0.9 * output(rb, 0, "bed.particles"));
}

TEST(Composition, JacobianEqualsFiniteDifferences) {
  Scene s = scene_from_text(scene(kAll));
  DaeSystem sys(*s.flowsheet);
  const int n = sys.size();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.2, 1.0);
  std::vector<double> y(n), yp(n);
  sys.initial_values(y);
  // a layer on every class, below each class's mass
  for (int i = 0; i < n; ++i) y[i] = std::abs(y[i]) * u(rng) + 1e-3 * u(rng), yp[i] = 0.1 * u(rng);
  const auto& names = s.flowsheet->state_names();
  for (int i = 0; i < n; ++i)
    if (names[i].rfind("bed.m_layer", 0) == 0) {
      const int k = std::stoi(names[i].substr(names[i].rfind('_') + 1));
      y[i] = 0.3 * y[s.flowsheet->state_id("bed.M_" + std::to_string(k))];
    }
  testing::expect_jacobian_matches_fd(sys, 0.0, y, yp, 2.5, 1e-6);
}

// The sieve-mill loop of paper 003 (section 7.5.1) with composed particles: cores fed as seeds, a layer sprayed on
// in the granulator, the discharge screened, the oversize milled and returned with the undersize, the product split
// in two. Every stream carries the layer's class flows; each solid's balance over the flowsheet closes.
const char* kLoop = R"(
scene: composed_sieve_mill_loop
t_end: 3 h
output: {n: 4}
solver: {rtol: 1e-9, atol: 1e-11}
particles:
  settings: {classes: 12, d_min: 2.0e-4, d_max: 3.0e-3, components: "core, layer"}
  params: {rho_s: 1040, eps_intra: 0, rho_layer: 1440}
units:
  seed: {type: solids_feed, settings: {component: core}, params: {mdot: 5 kg/h, d50: 400 um, sigma: 1.3}}
  gran:
    type: granulator
    settings: {discharge: unclassified, spray_component: layer}
    params: {bed_mass: 20 kg, k_discharge: 2e-4, d50_0: 800 um, sigma_0: 1.4, m_spray: 60 kg/h, w_spray: 0.3}
  sieve:
    type: sieve
    settings: {upper_curve: plitt, lower_curve: plitt}
    params: {upper_d_cut: 1.5 mm, lower_d_cut: 1.0 mm}
  mill: {type: mill, settings: {law: lognormal}, params: {d50: 450 um, sigma_g: 1.5}}
  recycle: {type: solids_mixer, settings: {inlets: 3}}
  split: {type: solids_splitter, params: {fraction: 0.3}}
  sample: {type: solids_product}
  product: {type: solids_product}
connections: [gran.discharge -> sieve.in, sieve.oversize -> mill.in, mill.out -> recycle.in1,
              sieve.undersize -> recycle.in2, seed.out -> recycle.in3, recycle.out -> gran.feed,
              sieve.product -> split.in, split.out1 -> sample.in, split.out2 -> product.in]
)";

TEST(Composition, SieveMillLoopCarriesEachComponentAndClosesItsBalance) {
  Scene s = scene_from_text(kLoop);
  const SimResult r = simulate(*s.flowsheet, s.options);
  const size_t last = r.t.size() - 1;
  EXPECT_LT(closure(s, r, "solids:core"), 1e-8);
  EXPECT_LT(closure(s, r, "solids:layer"), 1e-8);
  EXPECT_LT(closure(s, r, "solids"), 1e-8);
  // the layer left with the product: what was sprayed minus what the bed still holds
  const double sprayed = 60.0 / 3600 * 0.3 * r.t[last];
  const double out = output(r, last, "sample.balance_layer_out") + output(r, last, "product.balance_layer_out");
  EXPECT_GT(out, 0.01 * sprayed);
  EXPECT_NEAR(out + output(r, last, "gran.mass_layer"), sprayed, 1e-7 * sprayed);
  EXPECT_NEAR(output(r, last, "sample.balance_layer_out") / out, 0.3, 1e-9);  // the splitter's fraction
}

}  // namespace
}  // namespace granuflow
