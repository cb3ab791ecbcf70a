// Every registered unit type against the contract of unit.hpp, in scenes that exercise it (a new unit type without a
// conformance scene fails the first test):
//   * its Jacobian as assembled (analytic parts, class-coloured AD, reductions) equals plain forward AD of the whole
//     residual to round-off, and central finite differences, at a state inside a run, and its sparse form (what KLU
//     factors) holds the dense form's entries;
//   * the balances it takes part in close to the solver tolerance;
//   * every declared output exists and is finite at every output time;
//   * one flowsheet simulated from several threads at once gives the serial answer bit for bit (per-run workspaces).
// With GRANUFLOW_CONFORMANCE_SCENES set (scene files separated by ':'), the same checks run on those scenes alone, and
// the first test asks that every unit type from a plugin they load is exercised: how a plugin's units and kernels
// are held to the built-in ones' contract (docs/install_and_plugins.md; ctest plugin.example_conformance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "granuflow/dae_system.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
using testing::scene_from_text;

const char* kPbmMechanisms = R"(
scene: pbm_all_mechanisms
t_end: 2 s
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-12}
particles: {settings: {grid: geometric, q: 2, classes: 30, v_min: 1e-3}}
units:
  pbm:
    type: pbm_batch
    settings: {aggregation: sum, aggregation_scheme: cell_average, breakage: linear, growth: constant}
    params: {N0: 1, v0: 1 m3, growth_G: 0.01}
)";

// The 2-D population with every mechanism: DEM kernel (smooth efficiency), droplets split between liquid pivots
// (or a continuous flow of liquid), cross-section (or surface) weighting, drying.
std::string pbm_2d_scene(const std::string& spray = "droplets", const std::string& weight = "cross_section") {
  return R"(
scene: pbm_2d_all_mechanisms
t_end: 0.5 s
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-8}
particles: {settings: {grid: geometric, q: 2, classes: 5, v_min: 4e-9}, params: {rho_s: 1030 kg/m3, eps_intra: 0}}
units:
  g2:
    type: pbm_2d
    settings:
      liquid_classes: 6
      liquid_max: 2.4e-8
      aggregation: dem_collision
      agg_efficiency: smooth
      spray: )" +
         spray + R"(
      spray_weight: )" +
         weight + R"(
      psd_diameter: solid
      drying: surface
      agg_collisions_file: )" +
         testing::repo_path("flowsheets/data/sen2014_collisions_example.csv") + R"(
    params: {N0: 1000, d0: 2.1 mm, lc0: 0.2, spray_rate: 4e-6 m3/s, dry_flux: 1e-6 m/s, agg_psi0: 0.5)" +
         std::string(spray == "droplets" ? ", d_drop: 1.5 mm}" : "}") + "\n";
}

// Paper 003's continuous units in one loop: a wet granulator with aggregation and a classified discharge held at its
// set mass, a two-deck sieve (sharp upper deck, Molerus-Hoffmann lower deck), a Vogel-Peukert mill on the oversize,
// part of the undersize split off, and a mixer returning fines, milled oversize and fresh seeds.
const char* kSieveMillLoopHead = R"(
scene: sieve_mill_loop
t_end: 2 h
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {settings: {classes: 12, d_min: 2.0e-4, d_max: 3.0e-3}, params: {rho_s: 1500, eps_intra: 0.1}}
units:
  seed: {type: solids_feed, params: {mdot: 5 kg/h, d50: 400 um, sigma: 1.3, X: 0.02, T: 30 degC}}
  gran:
    type: granulator
    settings: {discharge: classified, bed_mass: controlled, classifier: plitt, drying: first_order,
               aggregation: constant, aggregation_scheme: fixed_pivot}
    params: {bed_mass: 20 kg, M_set: 22 kg, tau_c: 120 s, mdot_max: 0.5, d50_0: 800 um, sigma_0: 1.4,
             m_spray: 60 kg/h, w_spray: 0.3, X0: 0.01, tau_dry: 30 s, X_eq: 0.002, class_d_cut: 900 um, class_m: 4,
             agg_beta0: 1e-12}
  sieve:
    type: sieve
    settings: {upper_curve: sharp, lower_curve: molerus_hoffmann}
    params: {upper_d_cut: 1.5 mm, lower_d_cut: 1.0 mm, lower_k: 8}
  mill: {type: mill, settings: {law: vogel_peukert}, params: {W_m: 300, E_mat: 100, W_min: 20, q: 1.2}}
)";

// The loop's splitter, mixer, product sinks and connections, the same wet or dry.
const char* kLoopTail = R"(  split: {type: solids_splitter, params: {fraction: 0.8}}
  mix: {type: solids_mixer, settings: {inlets: 3}}
  product: {type: solids_product}
  fines_out: {type: solids_product}
connections: [seed.out -> mix.in1, sieve.undersize -> split.in, split.out1 -> mix.in2, split.out2 -> fines_out.in,
              mill.out -> mix.in3, mix.out -> gran.feed, gran.discharge -> sieve.in, sieve.oversize -> mill.in,
              sieve.product -> product.in]
)";

// The same loop dry (particles: water: false): no unit computes water, every solids stream passes on the seed
// feed's one zero; an unclassified discharge and a log-normal mill for variety.
const char* kDrySieveMillLoopHead = R"(
scene: dry_sieve_mill_loop
t_end: 2 h
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {settings: {classes: 12, d_min: 2.0e-4, d_max: 3.0e-3, water: false}, params: {rho_s: 1500, eps_intra: 0}}
units:
  seed: {type: solids_feed, params: {mdot: 5 kg/h, d50: 400 um, sigma: 1.3, T: 30 degC}}
  gran:
    type: granulator
    settings: {discharge: unclassified, bed_mass: controlled, aggregation: constant, aggregation_scheme: fixed_pivot}
    params: {bed_mass: 20 kg, M_set: 22 kg, tau_c: 120 s, mdot_max: 0.5, d50_0: 800 um, sigma_0: 1.4,
             m_spray: 60 kg/h, w_spray: 0.3, agg_beta0: 1e-12}
  sieve:
    type: sieve
    settings: {upper_curve: plitt, lower_curve: plitt}
    params: {upper_d_cut: 1.5 mm, lower_d_cut: 1.0 mm}
  mill: {type: mill, settings: {law: lognormal}, params: {d50: 450 um, sigma_g: 1.5}}
)";

// The dry loop with its bed mass held by a PI controller on the discharge rate instead of the ideal controller: a
// parameter driven by a state (k_discharge by the controller's output) and by an output (the controller's measurement
// by the granulator's mass, a sum over its classes).
const char* kPiLoopHead = R"(
scene: pi_sieve_mill_loop
t_end: 2 h
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {settings: {classes: 12, d_min: 2.0e-4, d_max: 3.0e-3, water: false}, params: {rho_s: 1500, eps_intra: 0}}
units:
  seed: {type: solids_feed, params: {mdot: 5 kg/h, d50: 400 um, sigma: 1.3, T: 30 degC}}
  gran:
    type: granulator
    settings: {discharge: unclassified, bed_mass: free}
    params: {bed_mass: 20 kg, d50_0: 800 um, sigma_0: 1.4, m_spray: 60 kg/h, w_spray: 0.3}
  sieve:
    type: sieve
    settings: {upper_curve: plitt, lower_curve: plitt}
    params: {upper_d_cut: 1.5 mm, lower_d_cut: 1.0 mm}
  mill: {type: mill, settings: {law: lognormal}, params: {d50: 450 um, sigma_g: 1.5}}
  lic:
    type: pi_controller
    settings: {measure: gran.mass, drive: gran.k_discharge, action: direct}
    params: {set_point: 22 kg, y_span: 20 kg, Kp: 2, Ti: 20 min, Tt: 20 min, u_min: 0, u_max: 0.02, u0: 1e-3}
)";

// The two-compartment bed of paper 003 (Eqs. (7.37)-(7.39)) run continuously: spray zone and drying zone exchanging
// particles, the drying zone fed and discharged (free hold-up), the water of the spray drying in both zones.
const char* kTwoZone = R"(
scene: two_zone_continuous
t_end: 600 s
output: {n: 5}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {settings: {classes: 15, d_min: 5.0e-4, d_max: 4.0e-3}, params: {rho_s: 1040, eps_intra: 0}}
units:
  seed: {type: solids_feed, params: {mdot: 10 kg/h, d50: 1.5 mm, sigma: 1.2}}
  spray: {type: spray_compartment, settings: {drying: first_order, growth_scheme: fv_upwind},
          params: {bed_mass: 0.08, tau: 4 s, X0: 0.01, tau_dry: 20 s, d50_0: 1.2 mm, sigma_0: 1.6}}
  dry: {type: drying_compartment, settings: {drying: first_order, discharge: unclassified},
        params: {bed_mass: 3.92, tau: 196 s, k_discharge: 1e-3, X0: 0.01, tau_dry: 20 s, d50_0: 1.2 mm,
                 sigma_0: 1.6}}
  product: {type: solids_product}
connections: [spray.out -> dry.in, dry.out -> spray.in, seed.out -> dry.feed, dry.discharge -> product.in]
)";

// The review's drying closures (paper 000): the headline with a drying curve and a drying surface other than the
// defaults in its bed (the bed's moisture stays below the critical one: the curve acts on every class).
Scene drying_closures_scene(const std::string& settings, const std::string& params) {
  std::ifstream f(testing::repo_path("flowsheets/stoeckl_gf25_batch.yaml"));
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str();
  const std::string from = "    params: {bed_mass: 15 kg,";
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos)
    text.replace(at, from.size(), "    settings: {" + settings + "}\n    params: {" + params + "bed_mass: 15 kg,");
  return scene_from_text(text);
}

// The two-zone bed with a drying curve and surface in both compartments (paper 000, sections 5.2, 5.4.1, in paper
// 003's chambers).
std::string two_zone_with_curve(const std::string& two_zone) {
  std::string text = two_zone;
  for (const std::string unit : {"spray: {type: spray_compartment, settings: {",
                                 "dry: {type: drying_compartment, "
                                 "settings: {"}) {
    const size_t at = text.find(unit);
    EXPECT_NE(at, std::string::npos) << unit;
    text.insert(at + unit.size(), "drying_curve: gamma, drying_surface: coverage, ");
  }
  const size_t p = text.find("params: {bed_mass: 3.92");
  text.insert(p + 9, "drying_gamma: 3, X_cr: 0.012, ");
  return text;
}

// Scenes named by GRANUFLOW_CONFORMANCE_SCENES, if set.
const char* kUserScenes = std::getenv("GRANUFLOW_CONFORMANCE_SCENES");

std::vector<std::pair<std::string, Scene>> user_scenes() {
  std::vector<std::pair<std::string, Scene>> v;
  std::string list = kUserScenes;
  for (size_t start = 0; start <= list.size();) {
    const size_t end = std::min(list.find(':', start), list.size());
    if (end > start)
      v.emplace_back(list.substr(start, end - start), load_scene(list.substr(start, end - start), units::builtin()));
    start = end + 1;
  }
  return v;
}

// Scenes and the unit types each one covers.
std::vector<std::pair<std::string, Scene>> scenes() {
  if (kUserScenes) return user_scenes();
  std::vector<std::pair<std::string, Scene>> v;
  v.emplace_back("headline", scene_from_file("flowsheets/stoeckl_gf25_batch.yaml"));
  v.emplace_back("demo tanks", scene_from_file("flowsheets/demo_tanks.yaml"));
  v.emplace_back("continuous dryer", scene_from_file("flowsheets/continuous_drying_bed.yaml"));
  v.emplace_back("pbm", scene_from_text(kPbmMechanisms));
  v.emplace_back("pbm 2d", scene_from_text(pbm_2d_scene()));
  v.emplace_back("pbm 2d, surface-weighted droplets", scene_from_text(pbm_2d_scene("droplets", "surface")));
  v.emplace_back("pbm 2d, continuous liquid", scene_from_text(pbm_2d_scene("continuous", "surface")));
  v.emplace_back("sieve-mill loop", scene_from_text(std::string(kSieveMillLoopHead) + kLoopTail));
  v.emplace_back("dry sieve-mill loop", scene_from_text(std::string(kDrySieveMillLoopHead) + kLoopTail));
  v.emplace_back("two-zone bed", scene_from_text(kTwoZone));
  v.emplace_back("drying: gamma curve, coverage",
                 drying_closures_scene("drying_curve: gamma, drying_surface: coverage", "drying_gamma: 3, "));
  v.emplace_back("drying: cubic curve, droplet height",
                 drying_closures_scene("drying_curve: cubic, drying_surface: droplet_height",
                                       "drying_A: 0.5, drying_B: 0.3, drying_C: 0.2, drying_theta: 1.2, "));
  v.emplace_back("drying: correction, spray filtration, Stokes report",
                 drying_closures_scene("drying_surface: correction, spray_deposition: filtration, "
                                       "stokes_deformation: report",
                                       "drying_f_surface: 0.6, filtration_length: 1e-3, "));
  v.emplace_back("two-zone bed, gamma curve, coverage", scene_from_text(two_zone_with_curve(kTwoZone)));
  v.emplace_back("headline, PI on the gas temperature",
                 scene_from_file("flowsheets/stoeckl_gf25_batch_controlled.yaml"));
  v.emplace_back("sieve-mill loop, PI on the bed mass", scene_from_text(std::string(kPiLoopHead) + kLoopTail));
  return v;
}

TEST(UnitConformance, EveryRegisteredUnitTypeIsExercised) {
  std::set<std::string> covered;
  for (auto& [name, s] : scenes())
    for (const auto& u : s.flowsheet->units()) covered.insert(u.unit->type());
  const bool plugins = kUserScenes != nullptr;  // then the types plugins brought, else the built-in ones
  for (const auto& type : units::builtin().names())
    if (units::builtin().origin(type).empty() != plugins) {
      EXPECT_TRUE(covered.count(type)) << type << " has no scene";
    }
}

// The sparse Jacobian (values in the pattern's order, what KLU factors) holds the dense one's entries: units with
// an analytic Jacobian write a dense sink column by column and other sinks entry by entry (the population engine).
void expect_sparse_jacobian_holds_the_dense_one(DaeSystem& full, double t, std::vector<double>& y,
                                                std::vector<double>& yp, double cj) {
  const int m = full.size();
  std::vector<double> dense(size_t(m) * m), values(full.pattern().nnz());
  full.jacobian(t, y.data(), yp.data(), cj, dense.data(), nullptr);
  full.jacobian(t, y.data(), yp.data(), cj, nullptr, values.data());
  const SparsityPattern& pat = full.pattern();
  std::vector<double> from_sparse(size_t(m) * m, 0.0);
  for (int c = 0; c < m; ++c)
    for (int k = pat.col_ptr[c]; k < pat.col_ptr[c + 1]; ++k) from_sparse[size_t(c) * m + pat.row_idx[k]] = values[k];
  int mismatches = 0;
  for (size_t k = 0; k < dense.size(); ++k)
    if (std::abs(dense[k] - from_sparse[k]) > 1e-12 * std::max(1.0, std::abs(dense[k])) && ++mismatches <= 5)
      ADD_FAILURE() << "entry (" << k % m << ", " << k / m << "): dense " << dense[k] << ", sparse " << from_sparse[k];
  EXPECT_EQ(mismatches, 0);
}

TEST(UnitConformance, JacobianEqualsPlainAdAndFiniteDifferences) {
  for (auto& [name, s] : scenes()) {
    SCOPED_TRACE(name);
    SimOptions o = s.options;
    const double t1 = 0.3 * o.t_end;
    o.t_out = {0, t1};
    const SimResult r = simulate(*s.flowsheet, o);
    const int n = r.n_states();
    std::vector<double> y(r.y.begin() + n, r.y.begin() + 2 * n), yp(r.yp.begin() + n, r.yp.begin() + 2 * n);
    DaeSystem full(*s.flowsheet, false);  // every state, explicit ones included
    testing::expect_jacobian_matches_reference(full, t1, y, yp, 3.3, 1e-12);
    testing::expect_jacobian_matches_fd(full, t1, y, yp, 3.3, 2e-6);
    expect_sparse_jacobian_holds_the_dense_one(full, t1, y, yp, 3.3);
  }
}

TEST(UnitConformance, BalancesCloseAndOutputsAreFinite) {
  for (auto& [name, s] : scenes()) {
    SCOPED_TRACE(name);
    const SimResult r = simulate(*s.flowsheet, s.options);
    const size_t no = r.output_names.size(), last = r.t.size() - 1;
    ASSERT_EQ(no, static_cast<size_t>(s.flowsheet->n_outputs()));
    for (size_t k = 0; k < r.t.size(); ++k)
      for (size_t j = 0; j < no; ++j) ASSERT_TRUE(std::isfinite(r.outputs[k * no + j])) << r.output_names[j];
    // per quantity: hold-up change = in - out, over the outputs whose declared role says so
    std::map<std::string, std::array<double, 4>> acc;  // in, out, hold0, hold1
    size_t j = 0;
    for (const auto& u : s.flowsheet->units())
      for (const auto& out : u.spec.outputs()) {
        const double a = r.outputs[j], b = r.outputs[last * no + j];
        ++j;
        if (out.quantity.empty()) continue;
        auto& q = acc[out.quantity];
        if (out.role == OutputRole::kBalanceIn) q[0] += b - a;
        if (out.role == OutputRole::kBalanceOut) q[1] += b - a;
        if (out.role == OutputRole::kBalanceHold) q[2] += a, q[3] += b;
      }
    if (name != "pbm") {
      EXPECT_FALSE(acc.empty());
    }
    for (const auto& [q, v] : acc) {
      const double scale = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2]), std::abs(v[3])});
      EXPECT_LT(std::abs(v[3] - v[2] - (v[0] - v[1])), 10 * s.options.rtol * scale) << q;
    }
  }
}

TEST(UnitConformance, OneFlowsheetFromFourThreadsGivesTheSerialAnswer) {
  for (auto& [name, s] : scenes()) {
    SCOPED_TRACE(name);
    SimOptions o = s.options;
    if (name == "headline") o.sensitivities = {"bed.agg_ln_beta0", "particles.rho_s"};
    const SimResult ref = simulate(*s.flowsheet, o);
    std::vector<SimResult> got(4);
    std::vector<std::thread> threads;
    Flowsheet& fs = *s.flowsheet;  // a lambda cannot capture a structured binding before C++20 (clang)
    for (int k = 0; k < 4; ++k)
      threads.emplace_back([&, k] {
        for (int rep = 0; rep < 3; ++rep) got[k] = simulate(fs, o);
      });
    for (auto& t : threads) t.join();
    for (const auto& g : got) {
      EXPECT_EQ(g.y, ref.y);
      EXPECT_EQ(g.outputs, ref.outputs);
      EXPECT_EQ(g.sens, ref.sens);
      EXPECT_EQ(g.output_sens, ref.output_sens);
    }
  }
}

}  // namespace
}  // namespace granuflow
