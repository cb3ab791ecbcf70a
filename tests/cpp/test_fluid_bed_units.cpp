// The fluid-bed unit models of paper 001, each against an exact answer where one exists, then the headline
// scene: exact Jacobian, sensitivities, conservation, grid convergence and the published behaviour.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "granuflow/properties.hpp"
#include "granuflow/simulator.hpp"
#include "kernels/drying/paper001_drying.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::output;
using testing::scene_from_file;
using testing::scene_from_text;

double state(const Scene& s, const SimResult& r, size_t k, const std::string& name) {
  return r.state(k, s.flowsheet->state_id(name));
}

// Relative closure |dHold - (in - out)| / max(...) over every output whose declared role is a balance term of q.
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

const char* kChamber = R"(
scene: chamber_only
t_end: 20 s
output: {times: [0 s, 1 s, 3 s, 20 s]}
solver: {rtol: 1e-10, atol: 1e-12}
units:
  inlet: {type: gas_inlet, params: {V_dot: 700 m3/h, T: 60 degC, Y: 5 g/kg}}
  gas: {type: chamber_gas, params: {m_gas: 1.53, T0: 20 degC, Y0: 12 g/kg}}
  exhaust: {type: gas_outlet}
connections: [inlet.out -> gas.in, gas.out -> exhaust.in]
)";

TEST(ChamberGas, RelaxesToInletStateWithTimeConstantHoldupOverFlow) {
  Scene s = scene_from_text(kChamber);
  SimOptions o = s.options;
  const SimResult r = simulate(*s.flowsheet, o);
  const double m = state(s, r, 0, "inlet.mdot"), tau = 1.53 / m;
  // dry-air flow of 700 m3/h humid air at 60 degC, 1 atm, Y = 5 g/kg: (p - p_v) M_air / (R T) V
  const double pv = 101325.0 * 0.005 / (0.005 + 0.01801528 / 0.0289647);
  EXPECT_NEAR(m, 700.0 / 3600.0 * (101325.0 - pv) * 0.0289647 / (8.314462618 * 333.15), 1e-12);
  const double h_in = props::humid_air_enthalpy(333.15, 0.005), h0 = props::humid_air_enthalpy(293.15, 0.012);
  for (size_t k = 0; k < r.t.size(); ++k) {
    const double e = std::exp(-r.t[k] / tau);
    const double y = 0.005 + (0.012 - 0.005) * e, h = h_in + (h0 - h_in) * e;  // well-mixed hold-up, exact
    EXPECT_NEAR(state(s, r, k, "gas.Y"), y, 1e-9);
    EXPECT_NEAR(state(s, r, k, "gas.T"), props::humid_air_temperature(h, y), 1e-6);
  }
  // the integrals of the flows are quadratures: closure to the solver tolerance (rtol 1e-10)
  EXPECT_LT(closure(s, r, "water"), 1e-9);
  EXPECT_LT(closure(s, r, "energy"), 1e-9);
}

TEST(WallHeatLoss, SteadyChamberTemperatureBalancesEnthalpyFlowAndLoss) {
  std::string text = kChamber;
  text = std::regex_replace(text, std::regex("  exhaust: \\{type: gas_outlet\\}"),
                            "  exhaust: {type: gas_outlet}\n  wall: {type: wall_heat_loss}");
  text =
      std::regex_replace(text, std::regex("gas.out -> exhaust.in\\]"), "gas.out -> exhaust.in, gas.wall -> wall.in]");
  Scene s = scene_from_text(text);
  const SteadyResult ss = solve_steady_state(*s.flowsheet, SteadyOptions{});
  // the inlet is explicit (inlined): its dry-air flow from the parameters, as in the test above
  const double pv = 101325.0 * 0.005 / (0.005 + 0.01801528 / 0.0289647);
  const double m = 700.0 / 3600.0 * (101325.0 - pv) * 0.0289647 / (8.314462618 * 333.15);
  const double c = 1006.0 + 0.005 * 1870.0, ka = 13.8 * 7.3;  // Eq. (84), Table 6 and 8
  // m c (T_in - T) = k A (T - T_env)
  const double t = (m * c * 333.15 + ka * 293.15) / (m * c + ka);
  EXPECT_NEAR(ss.y[s.flowsheet->state_id("gas.T")], t, 1e-8);
  EXPECT_NEAR(ss.y[s.flowsheet->state_id("wall.Q")], ka * (t - 293.15), 1e-6);
}

TEST(DropletEvaporation, RateEqualsEquation66ByHand) {
  Scene s = scene_from_text(R"(
scene: droplets
t_end: 1 s
output: {n: 2}
units:
  inlet: {type: gas_inlet, params: {V_dot: 700 m3/h, T: 60 degC, Y: 5 g/kg}}
  gas: {type: chamber_gas, params: {T0: 60 degC, Y0: 5 g/kg}}
  exhaust: {type: gas_outlet}
  nozzle: {type: spray_nozzle, params: {mdot: 90 g/min, T: 10 degC}}
  droplets: {type: droplet_evaporation}
  sink: {type: liquid_product}
connections: [inlet.out -> gas.in, gas.out -> exhaust.in, nozzle.out -> droplets.spray, gas.state -> droplets.gas,
              droplets.vapour -> gas.evap, droplets.deposit -> sink.in]
)");
  const SimResult r = simulate(*s.flowsheet, s.options);
  // p_sat(60 degC) = 1000 exp(16.262 - 3800 / (226.3 + 60)) = 19870.0 Pa            (Eq. (69))
  // Y_eq = 0.621977 * 19870.0 / (101325 - 19870.0) = 0.151723                         (Eq. (68))
  // A = 6 * 1.5e-3 / (1000 * 30e-6) = 0.3 m^2/s; m_evap = 3e-3 * 0.3 * (0.151723 - 0.005)  (Eq. (66))
  const double psat = 1000.0 * std::exp(16.262 - 3800.0 / (226.3 + 60.0));
  const double yeq = 0.01801528 / 0.0289647 * psat / (101325.0 - psat);
  EXPECT_NEAR(psat, 19870.0, 0.5);
  EXPECT_NEAR(yeq, 0.151723, 1e-6);
  EXPECT_NEAR(state(s, r, 0, "droplets.m_evap"), 3e-3 * 0.3 * (yeq - 0.005), 1e-12);
  EXPECT_NEAR(state(s, r, 0, "droplets.m_dep") + state(s, r, 0, "droplets.m_evap"), 1.5e-3, 1e-15);
  EXPECT_LT(closure(s, r, "water"), 10 * s.options.rtol);
  EXPECT_LT(closure(s, r, "energy"), 10 * s.options.rtol);
}

const char* kDrying = R"(
scene: drying_only
t_end: 8 h
output: {n: 9}
solver: {rtol: 1e-8, atol: 1e-10}
particles: {}
units:
  inlet: {type: gas_inlet, params: {V_dot: 700 m3/h, T: 60 degC, Y: 5 g/kg}}
  gas: {type: chamber_gas}
  exhaust: {type: gas_outlet}
  bed: {type: fluid_bed, settings: {aggregation: none, breakage: none}, params: {X0: 0.12, T0: 30 degC}}
connections: [inlet.out -> gas.in, gas.out -> exhaust.in, inlet.state -> bed.inlet, gas.state -> bed.gas,
              bed.vapour -> gas.drying, gas.solids -> bed.heat]
)";

TEST(FluidBed, DriesToTheBetEquilibriumOfTheInletAir) {
  Scene s = scene_from_text(kDrying);
  const SimResult r = simulate(*s.flowsheet, s.options);
  const size_t last = r.t.size() - 1;
  // At the end the bed sits at the inlet state: T_S = T_in, X = X_eq(a) with a = p_v(Y_in) / p_sat(T_in).
  const double pv = 101325.0 * 0.005 / (0.005 + 0.01801528 / 0.0289647);
  const double a = pv / (1000.0 * std::exp(16.262 - 3800.0 / (226.3 + 60.0)));
  const double xeq = 0.037 * 11.9 * a / ((1 - a) * (1 + 10.9 * a));  // Eq. (81), Table 8
  EXPECT_NEAR(state(s, r, last, "bed.T"), 333.15, 1e-4);
  EXPECT_NEAR(output(r, last, "bed.moisture"), xeq, 1e-6);
  EXPECT_GT(output(r, 0, "bed.moisture"), 0.1);
  EXPECT_LT(closure(s, r, "water"), 1e-7);  // quadratures: closure to the tolerance, rtol 1e-8
  EXPECT_LT(closure(s, r, "energy"), 1e-7);
  EXPECT_LT(closure(s, r, "solids"), 1e-12);  // no solids flow: the bed keeps its solids to round-off
}

TEST(FluidBed, StructuredJacobianMatchesPlainAdAndFiniteDifferencesForEachMechanism) {
  // the engine's analytic part plus class-coloured AD with reductions: check each branch against plain AD
  for (const std::string settings :
       {"{aggregation: none, breakage: none}", "{aggregation: constant, breakage: none}",
        "{aggregation: constant, aggregation_scheme: cell_average, breakage: vogel_peukert, sel_size_unit: mm}",
        "{aggregation: constant, breakage: vogel_peukert, breakage_scheme: cell_mass}"}) {
    std::string text =
        std::regex_replace(std::string(kDrying), std::regex("\\{aggregation: none, breakage: none\\}"), settings);
    if (settings.find("constant") != std::string::npos)
      text = std::regex_replace(text, std::regex("params: \\{X0: 0.12, T0: 30 degC\\}"),
                                "params: {X0: 0.12, T0: 30 degC, agg_beta0: 1e-13}");  // beta N ~ 1e-3 / s
    Scene s = scene_from_text(text);
    SimOptions o = s.options;
    o.t_out = {0, 300};
    const SimResult r = simulate(*s.flowsheet, o);
    const int n = r.n_states();
    std::vector<double> y(r.y.begin() + n, r.y.begin() + 2 * n), yp(r.yp.begin() + n, r.yp.begin() + 2 * n);
    DaeSystem sys(*s.flowsheet);
    SCOPED_TRACE(settings);
    testing::expect_jacobian_matches_fd(sys, 300.0, y, yp, 3.0, 2e-6);
    DaeSystem full(*s.flowsheet, false);
    testing::expect_jacobian_matches_reference(full, 300.0, y, yp, 3.0, 1e-12);
  }
}

// The shipped continuous dryer: a log-normal feed, a well-mixed discharge at k = 1e-3 /s, no aggregation or breakage.
Scene continuous_bed(const std::string& bed_settings = "aggregation: none") {
  Scene s = scene_from_file("flowsheets/continuous_drying_bed.yaml");
  s = scene_from_text(std::regex_replace(s.text, std::regex("aggregation: none"), bed_settings));
  s.options.rtol = s.options.atol = 1e-10;
  return s;
}

TEST(FluidBed, ContinuousHoldUpRelaxesToFeedOverDischargeRateWithTheFeedPsd) {
  Scene s = continuous_bed();
  const SimResult r = simulate(*s.flowsheet, s.options);
  const Flowsheet& fs = *s.flowsheet;
  const int n = 12;
  const double k = 1e-3, feed = 36.0 / 3600.0;
  double fsum = 0;
  std::vector<double> f(n), m0(n);
  for (int i = 0; i < n; ++i) {
    f[i] = state(s, r, 0, "feed.mdot_" + std::to_string(i)) / feed;  // the feed's class fractions
    m0[i] = state(s, r, 0, "bed.M_" + std::to_string(i));
    fsum += f[i];
  }
  EXPECT_NEAR(fsum, 1.0, 1e-12);
  // dM_i/dt = f_i F - k M_i, each class on its own: M_i(t) = f_i F / k + (M_i(0) - f_i F / k) exp(-k t)
  for (size_t j = 0; j < r.t.size(); ++j) {
    const double e = std::exp(-k * r.t[j]);
    for (int i = 0; i < n; ++i) {
      const double exact = f[i] * feed / k + (m0[i] - f[i] * feed / k) * e;
      EXPECT_NEAR(state(s, r, j, "bed.M_" + std::to_string(i)), exact, 1e-8 * feed / k) << "class " << i;
    }
  }
  // the discharge carries the bed's moisture and temperature
  const size_t last = r.t.size() - 1;
  const double m_out = output(r, last, "product.mdot");
  double m_bed = 0, w_bed = 0;
  for (int i = 0; i < n; ++i)
    m_bed += state(s, r, last, "bed.M_" + std::to_string(i)), w_bed += state(s, r, last, "bed.W_" + std::to_string(i));
  EXPECT_NEAR(m_out, k * m_bed, 1e-12);
  EXPECT_NEAR(output(r, last, "bed.moisture"), w_bed / m_bed, 1e-12);
  EXPECT_LT(output(r, last, "bed.moisture"), 0.08);  // dried on the way
  for (const char* q : {"solids", "water", "energy"}) EXPECT_LT(closure(s, r, q), 1e-8) << q;

  // the steady state: hold-up F / k with the feed's size distribution, found directly
  const SteadyResult ss = solve_steady_state(*s.flowsheet, SteadyOptions{});
  EXPECT_TRUE(ss.conserved.empty());  // feed and discharge: no hold-up is conserved
  double m_ss = 0;
  for (int i = 0; i < n; ++i) {
    const double mi = ss.y[fs.state_id("bed.M_" + std::to_string(i))];
    EXPECT_NEAR(mi, f[i] * feed / k, 1e-9 * feed / k) << "class " << i;
    m_ss += mi;
  }
  EXPECT_NEAR(m_ss, feed / k, 1e-9 * feed / k);
}

TEST(FluidBed, DischargeAndFeedPortsKeepTheJacobianExact) {
  Scene s = continuous_bed("aggregation: constant");
  s.flowsheet->set_param("bed.agg_beta0", 1e-13);
  SimOptions o = s.options;
  o.t_out = {0, 300};
  const SimResult r = simulate(*s.flowsheet, o);
  const int n = r.n_states();
  std::vector<double> y(r.y.begin() + n, r.y.begin() + 2 * n), yp(r.yp.begin() + n, r.yp.begin() + 2 * n);
  DaeSystem sys(*s.flowsheet);
  testing::expect_jacobian_matches_fd(sys, 300.0, y, yp, 3.0, 2e-6);
  DaeSystem full(*s.flowsheet, false);
  testing::expect_jacobian_matches_reference(full, 300.0, y, yp, 3.0, 1e-12);
}

// ---------------------------------------------------------------- the headline scene

Scene headline(int classes = 10, const std::string& bed_settings = "") {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  if (classes == 10 && bed_settings.empty()) return s;
  std::string text = std::regex_replace(s.text, std::regex("classes: 10"), "classes: " + std::to_string(classes));
  if (!bed_settings.empty())
    text = std::regex_replace(text, std::regex("    type: fluid_bed\n"),
                              "    type: fluid_bed\n    settings: {" + bed_settings + "}\n");
  return scene_from_text(text);
}

TEST(Gf25Scene, JacobianIsExactAtAStateInsideTheRun) {
  for (const std::string split : {"class_surface", "literal"}) {
    SCOPED_TRACE(split);
    Scene s =
        scene_from_text(std::regex_replace(headline().text, std::regex("    type: spray_zone\n"),
                                           "    type: spray_zone\n    settings: {liquid_split: " + split + "}\n"));
    SimOptions o = s.options;
    o.t_out = {0, 600};
    const SimResult r = simulate(*s.flowsheet, o);
    // the integrator's unknowns exclude the inlined explicit states, which come last in the full vector
    DaeSystem sys(*s.flowsheet);
    const int n = r.n_states(), k = sys.size();
    std::vector<double> y(r.y.begin() + n, r.y.begin() + n + k), yp(r.yp.begin() + n, r.yp.begin() + n + k);
    testing::expect_jacobian_matches_fd(sys, 600.0, y, yp, 7.5, 2e-6);
    // over all states (nothing inlined): the structured Jacobian equals plain forward AD of every unit
    DaeSystem full(*s.flowsheet, false);
    std::vector<double> yf(r.y.begin() + n, r.y.begin() + 2 * n), ypf(r.yp.begin() + n, r.yp.begin() + 2 * n);
    testing::expect_jacobian_matches_reference(full, 600.0, yf, ypf, 7.5, 1e-12);
  }
}

// A binder solution (docs/binder_granulation.md): the layering's analytic Jacobian (class masses and water, the
// deposit rate, its solids fraction and the growth shape) is exact too.
TEST(Gf25Scene, JacobianIsExactWithABinderSolution) {
  Scene s =
      scene_from_text(std::regex_replace(headline().text, std::regex("T: 10 degC, t_on"), "T: 10 degC, w: 0.3, t_on"));
  SimOptions o = s.options;
  o.t_out = {0, 600};
  const SimResult r = simulate(*s.flowsheet, o);
  DaeSystem sys(*s.flowsheet);
  const int n = r.n_states(), k = sys.size();
  std::vector<double> y(r.y.begin() + n, r.y.begin() + n + k), yp(r.yp.begin() + n, r.yp.begin() + n + k);
  testing::expect_jacobian_matches_fd(sys, 600.0, y, yp, 7.5, 2e-6);
  DaeSystem full(*s.flowsheet, false);
  std::vector<double> yf(r.y.begin() + n, r.y.begin() + 2 * n), ypf(r.yp.begin() + n, r.yp.begin() + 2 * n);
  testing::expect_jacobian_matches_reference(full, 600.0, yf, ypf, 7.5, 1e-12);
}

// The inlined Jacobian keeps explicit units' outer products factored and multiplies only the nonzeros it finds
// among the entries the units wrote: it must equal J_RR - J_RS J_SS^-1 J_SR of the Jacobian over all states, formed
// densely here. It is evaluated at the run's start first, so the second evaluation also shows that the first left
// nothing behind in the matrix over every state (each evaluation clears only the entries it wrote).
void expect_inlined_jacobian_is_schur_complement(Scene& s, double t) {
  SimOptions o = s.options;
  o.t_out = {0, t};
  const SimResult r = simulate(*s.flowsheet, o);
  DaeSystem sys(*s.flowsheet), full(*s.flowsheet, false);
  const int n = sys.size(), nf = full.size();
  ASSERT_GT(nf, n);
  std::vector<double> y(r.y.begin() + nf, r.y.begin() + nf + n), yp(r.yp.begin() + nf, r.yp.begin() + nf + n);
  std::vector<double> yf(nf), ypf(nf), jac(size_t(n) * n), jf(size_t(nf) * nf);
  const double cj = 0.37;
  sys.jacobian(0.0, r.y.data(), r.yp.data(), 2.0 * cj, jac.data(), nullptr);
  sys.extend(t, y.data(), yp.data(), yf.data(), ypf.data());
  sys.jacobian(t, y.data(), yp.data(), cj, jac.data(), nullptr);
  full.jacobian(t, yf.data(), ypf.data(), cj, jf.data(), nullptr);
  const Eigen::Map<const Eigen::MatrixXd> J(jf.data(), nf, nf), inl(jac.data(), n, n);
  const int m = nf - n;
  const Eigen::MatrixXd schur =
      J.topLeftCorner(n, n) - J.topRightCorner(n, m) * J.bottomRightCorner(m, m).lu().solve(J.bottomLeftCorner(m, n));
  const double scale = schur.cwiseAbs().maxCoeff();
  EXPECT_LT((inl - schur).cwiseAbs().maxCoeff(), 1e-12 * scale);
  // the correction is not trivially zero: explicit states change the integrated rows
  EXPECT_GT((schur - J.topLeftCorner(n, n)).cwiseAbs().maxCoeff(), 1e-6 * scale);
}

TEST(Gf25Scene, InlinedJacobianIsTheSchurComplementOfTheFullOne) {
  for (int classes : {10, 20}) {
    SCOPED_TRACE(classes);
    Scene s = headline(classes);
    expect_inlined_jacobian_is_schur_complement(s, 900.0);
  }
}

TEST(SieveMillLoop, InlinedJacobianIsTheSchurComplementOfTheFullOne) {
  // explicit units reading explicit units: the sieve feeds the mill, both feed the recycle mixer
  const std::string text = scene_from_file("flowsheets/continuous_layering_sieve_mill.yaml").text;
  ASSERT_NE(text.find("classes: 100"), std::string::npos);
  Scene s = scene_from_text(std::regex_replace(text, std::regex("classes: 100"), "classes: 30"));
  expect_inlined_jacobian_is_schur_complement(s, 5.0 * 3600.0);
}

TEST(Gf25Scene, SensitivitiesEqualFiniteDifferences) {
  // the bed's parameter tables (particle mass, breakage matrix) and its initial PSD carry parameter derivatives too
  const std::vector<std::string> params{"bed.agg_ln_beta0", "bed.sel_k_break", "wall.k_wall",     "bed.X_cr",
                                        "droplets.k_evap",  "particles.rho_s", "bed.frag_q_frag", "bed.frag_d_frag_min",
                                        "bed.d50_0",        "bed.sigma_0"};
  Scene s = headline();
  SimOptions o = s.options;
  o.t_out = {0, 1200};
  o.rtol = 1e-9;
  o.atol = 1e-11;
  o.sensitivities = params;
  const SimResult r = simulate(*s.flowsheet, o);
  const int n = r.n_states();
  for (const std::string obs : {"bed.M_9", "gas.T", "bed.W_3"}) {
    const int i = s.flowsheet->state_id(obs);
    for (size_t k = 0; k < params.size(); ++k) {
      const double p = s.flowsheet->param(params[k]);
      // integration noise (rtol 1e-10) stays below 1e-6 relative with these steps
      const double h = params[k] == "bed.agg_ln_beta0" ? 0.01 : 1e-2 * std::abs(p);
      auto run = [&](double v) {
        Scene q = headline();
        q.flowsheet->set_param(params[k], v);
        SimOptions oo = o;
        oo.rtol = 1e-10;
        oo.atol = 1e-12;
        oo.sensitivities.clear();
        return simulate(*q.flowsheet, oo).state(1, i);
      };
      const double d1 = (run(p + h) - run(p - h)) / (2 * h), d2 = (run(p + h / 2) - run(p - h / 2)) / h;
      const double fd = (4 * d2 - d1) / 3;  // Richardson: truncation O(h^4)
      const double sens = r.sens[(1 * params.size() + k) * n + i];
      EXPECT_NEAR(sens, fd, 5e-5 * std::abs(fd) + 1e-9 * std::abs(r.state(1, i)) / std::abs(p))
          << obs << " / " << params[k];
    }
  }
}

TEST(Gf25Scene, BalancesCloseAndTheBedBehavesAsPublished) {
  Scene s = headline();
  const SimResult r = simulate(*s.flowsheet, s.options);
  EXPECT_LT(closure(s, r, "water"), s.options.rtol);
  EXPECT_LT(closure(s, r, "solids"), s.options.rtol);
  EXPECT_LT(closure(s, r, "energy"), s.options.rtol);
  const size_t last = r.t.size() - 1;
  auto at = [&](double t_min) { return static_cast<size_t>(std::lround(t_min * 60.0 / (r.t[1] - r.t[0]))); };
  // moisture rises after spray start and levels off: 90 % of its total rise by 30 min
  const double x0 = output(r, 0, "bed.moisture"), x30 = output(r, at(30), "bed.moisture"),
               x60 = output(r, last, "bed.moisture");
  EXPECT_GT(x60, x0 * 1.3);
  EXPECT_GT(x30 - x0, 0.9 * (x60 - x0));
  // d50,3 grows, then approaches a plateau (agglomeration balanced by breakage) within about 30 min
  const double d0 = output(r, 0, "bed.d50"), d30 = output(r, at(30), "bed.d50"), d60 = output(r, last, "bed.d50");
  EXPECT_GT(d60, 1.5 * d0);
  EXPECT_GT(d30 - d0, 0.85 * (d60 - d0));
  // outlet gas temperature drops after the spray starts and settles
  const double t0 = state(s, r, 0, "gas.T"), t30 = state(s, r, at(30), "gas.T"), t60 = state(s, r, last, "gas.T");
  EXPECT_LT(t60, t0 - 10.0);
  EXPECT_LT(std::abs(t60 - t30), 0.1 * (t0 - t60));
  for (double v : r.outputs) EXPECT_FALSE(std::isnan(v));
}

TEST(Gf25Scene, GridRefinementConvergesTheMedianDiameter) {
  std::vector<double> d50;
  for (int classes : {10, 20, 40}) {
    Scene s = headline(classes);
    SimOptions o = s.options;
    o.t_out = {0, 3600};
    d50.push_back(output(simulate(*s.flowsheet, o), 1, "bed.d50"));
  }
  EXPECT_LT(std::abs(d50[2] - d50[1]), 0.5 * std::abs(d50[1] - d50[0]));
}

TEST(Gf25Scene, MechanismsLeftOutCostNoStates) {
  Scene full = headline();
  std::string text = full.text;
  text = std::regex_replace(text, std::regex("  droplets:\n    type: droplet_evaporation\n"), "");
  text = std::regex_replace(text, std::regex("  wall:\n    type: wall_heat_loss\n.*\n"), "");
  text = std::regex_replace(
      text, std::regex("  - (gas.state -> droplets.gas|droplets.vapour -> gas.evap|gas.wall -> wall.in)\n"), "");
  text =
      std::regex_replace(text, std::regex("droplets.deposit -> spray_zone.liquid"), "nozzle.out -> spray_zone.liquid");
  text = std::regex_replace(text, std::regex("  - nozzle.out -> droplets.spray\n"), "");
  text = std::regex_replace(text, std::regex("    type: fluid_bed\n"),
                            "    type: fluid_bed\n    settings: {breakage: none}\n");
  Scene lean = scene_from_text(text);
  EXPECT_EQ(full.flowsheet->n_states() - lean.flowsheet->n_states(), 4 + 1);        // droplet evaporation, wall
  EXPECT_EQ(full.flowsheet->n_quadratures() - lean.flowsheet->n_quadratures(), 1);  // the wall's energy lost
  EXPECT_EQ(full.flowsheet->param_names().size() - lean.flowsheet->param_names().size(), 4 + 3 + 6);  // + breakage
  const SimResult r = simulate(*lean.flowsheet, lean.options);
  EXPECT_LT(closure(lean, r, "water"), lean.options.rtol);
  EXPECT_LT(closure(lean, r, "energy"), lean.options.rtol);
  // without breakage and droplet evaporation, more liquid and no fragments: larger granules
  const SimResult rf = simulate(*full.flowsheet, full.options);
  EXPECT_GT(output(r, r.t.size() - 1, "bed.d50"), output(rf, rf.t.size() - 1, "bed.d50"));
}

}  // namespace
}  // namespace granuflow
