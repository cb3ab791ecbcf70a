// Work-precision of granuflow's population-balance schemes against the analytic solutions of docs/verification.md
// (N0 = v0 = 1, n(v, 0) = exp(-v)), through the full framework (Flowsheet + pbm_batch + simulate() on IDAS).
//
//   granuflow_bench_pbm [--json] [--repeats R] [--quick] [--case constant|sum|product|growth|breakage]
//                       [--integrators auto,ida,bdf,adams,erk] [--q Q] [--rtol R] [--scheme NAME]
//   granuflow_bench_pbm --refresh [--repeats R]   the cost of a kernel-parameter change (below)
//   granuflow_bench_pbm --jacobian [--repeats R]  the cost of a Jacobian and a residual (below)
//   (wired as `granuflow bench pbm --json`; baseline: /usr/bin/python3 tests/bench/scipy_fixed_pivot.py --json)
//
// One record per (case, method, integrator, q, rtol) with keys case, method (the scheme), integrator (solver.method
// asked for), integrator_ran (what ran: auto's choice), q, classes, rtol, tau, err_M0, err_M2, err_L1
// (relative L1 error of the mass density; null where no density is known), mass_drift (relative closure of
// the volume book-keeping), solve_ms (median wall time of simulate() over R repeats, one process), plus the
// solver counters and where the time goes: est_residual_ms / est_jacobian_ms / est_lu_ms are the counts times
// the per-call cost measured at the final state, setup_ms the DaeSystem construction (layout + configure).
// Grids: v in [2^-12, 2^15] (27 doublings, q classes per doubling) for aggregation and breakage; [2^-12, 2^7]
// for growth. atol = 1e-3 rtol (absolute; N0 = 1). Benchmarks never assert on time.
#include <sys/utsname.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <string>

#include "granuflow/dae_system.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/population/population.hpp"
#include "pbm_analytic.hpp"
#include "pbm_test_helpers.hpp"

namespace granuflow {
namespace {

namespace an = pbm_analytic;
using clk = std::chrono::steady_clock;

struct Case {
  std::string name;  // constant, sum, product, growth, breakage
  double tau;
  int doublings;
  std::vector<std::string> methods;
};

struct Record {
  std::string case_name, method, integrator, ran;
  int q = 0, classes = 0;
  double rtol = 0, tau = 0, err_m0 = 0, err_m2 = 0, err_l1 = NAN, drift = 0, solve_ms = 0;
  long steps = 0, jacobians = 0, residuals = 0, setups = 0;
  double setup_ms = 0, res_ms = 0, jac_ms = 0, lu_ms = 0;
};

double ms_since(clk::time_point t0) { return std::chrono::duration<double>(clk::now() - t0).count() * 1e3; }

pbm_test::Strings settings(const Case& c, const std::string& method, int q) {
  auto s = pbm_test::grid_settings(q, c.doublings);
  if (c.name == "growth") {
    s["growth"] = "constant";
    s["growth_scheme"] = method;
  } else if (c.name == "breakage") {
    s["breakage"] = "linear";
    s["fragments"] = "uniform_binary";
    s["breakage_scheme"] = method;
  } else {
    s["aggregation"] = c.name;
    s["aggregation_scheme"] = method;
  }
  return s;
}

pbm_test::Values params(const Case& c) {
  return c.name == "growth" ? pbm_test::Values{{"growth_G", 1.0}} : pbm_test::Values{};
}

void analytic(const Case& c, const kernels::Grid& g, double& m0, double& m2, std::vector<double>& cells) {
  const double t = c.tau;
  cells.clear();
  if (c.name == "constant") {
    m0 = an::scott_m0(t), m2 = an::scott_m2(t);
    cells = an::cell_volumes(g, [&](double v) { return an::scott_density(v, t); });
  } else if (c.name == "sum") {
    m0 = an::golovin_m0(t), m2 = an::golovin_m2(t);
    cells = an::cell_volumes(g, [&](double v) { return an::golovin_density(v, t); });
  } else if (c.name == "product") {
    m0 = an::product_m0(t), m2 = an::product_m2(t);
  } else if (c.name == "breakage") {
    m0 = an::ziff_m0(t), m2 = an::ziff_m2(t);
    cells = an::cell_volumes(g, [&](double v) { return an::ziff_density(v, t); });
  } else {
    m0 = an::growth_moment(0, t), m2 = an::growth_moment(2, t);
    cells = an::growth_cell_volumes(g, t);
  }
}

// Per-call costs at state y: residual, Jacobian assembly, dense LU (the framework's Eigen solver does the same).
void profile(Flowsheet& fs, const std::vector<double>& y, Record& rec) {
  DaeSystem sys(fs);
  const int n = sys.size();
  std::vector<double> yp(n, 0.0), r(n), J(size_t(n) * n);
  const int reps = std::max(20, 200000 / (n * n));
  auto t0 = clk::now();
  for (int k = 0; k < reps; ++k) sys.residual(0, y.data(), yp.data(), r.data());
  const double res = ms_since(t0) / reps;
  t0 = clk::now();
  for (int k = 0; k < reps / 4 + 1; ++k) sys.jacobian(0, y.data(), yp.data(), 10.0, J.data(), nullptr);
  const double jac = ms_since(t0) / (reps / 4 + 1);
  Eigen::Map<Eigen::MatrixXd> A(J.data(), n, n);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu(n);
  t0 = clk::now();
  for (int k = 0; k < reps / 4 + 1; ++k) {
    lu.compute(A);
    volatile double rc = lu.rcond();
    (void)rc;
  }
  const double fact = ms_since(t0) / (reps / 4 + 1);
  rec.res_ms = res * rec.residuals;
  rec.jac_ms = jac * rec.jacobians;
  rec.lu_ms = fact * rec.setups;
}

Record run(const Case& c, const std::string& method, const std::string& integrator, int q, double rtol, int repeats) {
  Record rec;
  rec.case_name = c.name, rec.method = method, rec.integrator = integrator, rec.q = q, rec.rtol = rtol, rec.tau = c.tau;
  const auto g = pbm_test::grid(q, c.doublings);
  rec.classes = g.size();
  std::vector<double> times, setups;
  pbm_test::Run r;
  for (int k = 0; k < repeats; ++k) {
    auto fs = pbm_test::flowsheet(settings(c, method, q), params(c));
    auto t0 = clk::now();
    { DaeSystem probe(*fs); }
    setups.push_back(ms_since(t0));
    fs = pbm_test::flowsheet(settings(c, method, q), params(c));
    t0 = clk::now();
    r = pbm_test::run(*fs, {0, c.tau}, rtol, 1e-3 * rtol, integrator);
    times.push_back(ms_since(t0));
  }
  std::sort(times.begin(), times.end());
  std::sort(setups.begin(), setups.end());
  rec.solve_ms = times[times.size() / 2];
  rec.setup_ms = setups[setups.size() / 2];
  const auto& st = r.result.stats;
  rec.steps = st.steps, rec.jacobians = st.jacobians, rec.residuals = st.residuals, rec.setups = st.linear_setups;
  rec.ran = st.method.substr(0, st.method.find(' ')) + (st.method.find("IDAS") != std::string::npos ? "-idas" : "");
  if (st.method.find(", then ") != std::string::npos) rec.ran += "+bdf";
  double m0, m2;
  std::vector<double> cells;
  analytic(c, g, m0, m2, cells);
  rec.err_m0 = pbm_test::moment(g, r.N(1), 0) / m0 - 1.0;
  rec.err_m2 = pbm_test::moment(g, r.N(1), 2) / m2 - 1.0;
  if (!cells.empty()) rec.err_l1 = an::l1_mass_error(g, r.N(1), cells);
  const double v0 = pbm_test::moment(g, r.N(0), 1);
  const double v1 = pbm_test::moment(g, r.N(1), 1) + r.state_or_zero(1, "volume_above") +
                    r.state_or_zero(1, "volume_below") - r.state_or_zero(1, "volume_grown");
  rec.drift = v1 / v0 - 1.0;
  auto fs = pbm_test::flowsheet(settings(c, method, q), params(c));
  profile(*fs, std::vector<double>(r.N(1), r.N(1) + r.result.state_names.size()), rec);
  return rec;
}

std::string meta_json() {
  char host[256] = "";
  gethostname(host, sizeof(host) - 1);
  std::string cpu;
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  std::string commit;
  if (FILE* p = popen("git -C " GRANUFLOW_SOURCE_DIR " rev-parse --short HEAD 2>/dev/null", "r")) {
    char buf[64] = "";
    if (fgets(buf, sizeof(buf), p)) commit = buf;
    pclose(p);
    commit.erase(commit.find_last_not_of(" \n") + 1);
  }
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M:%S", std::localtime(&now));
  return std::string("\"code\": \"granuflow\", \"machine\": \"") + host + "\", \"cpu\": \"" + cpu +
         "\", \"cores\": " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + ", \"commit\": \"" + commit +
         "\", \"date\": \"" + date + "\"";
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char b[40];
  std::snprintf(b, sizeof(b), "%.6g", v);
  return b;
}

void print(const Record& r, bool json, int repeats, const std::string& meta) {
  if (json) {
    std::printf(
        "{\"case\": \"%s\", \"method\": \"%s\", \"integrator\": \"%s\", \"integrator_ran\": \"%s\", \"q\": %d, "
        "\"classes\": %d, \"rtol\": %s, \"tau\": %s, \"err_M0\": %s, "
        "\"err_M2\": %s, \"err_L1\": %s, \"mass_drift\": %s, \"solve_ms\": %s, \"repeats\": %d, \"steps\": %ld, "
        "\"jacobians\": %ld, \"residuals\": %ld, \"linear_setups\": %ld, \"setup_ms\": %s, \"est_residual_ms\": %s, "
        "\"est_jacobian_ms\": %s, \"est_lu_ms\": %s, %s}\n",
        r.case_name.c_str(), r.method.c_str(), r.integrator.c_str(), r.ran.c_str(), r.q, r.classes, num(r.rtol).c_str(),
        num(r.tau).c_str(), num(r.err_m0).c_str(), num(r.err_m2).c_str(), num(r.err_l1).c_str(), num(r.drift).c_str(),
        num(r.solve_ms).c_str(), repeats, r.steps, r.jacobians, r.residuals, r.setups, num(r.setup_ms).c_str(),
        num(r.res_ms).c_str(), num(r.jac_ms).c_str(), num(r.lu_ms).c_str(), meta.c_str());
  } else {
    std::printf(
        "%-9s %-13s %-5s(%-9s) q=%d n=%3d rtol=%.0e  M0 %+.2e  M2 %+.3e  L1 %.2e  drift %+.1e  %8.3f ms  (setup "
        "%.2f, res %.2f, jac %.2f, LU %.2f; %ld steps)\n",
        r.case_name.c_str(), r.method.c_str(), r.integrator.c_str(), r.ran.c_str(), r.q, r.classes, r.rtol, r.err_m0,
        r.err_m2, r.err_l1, r.drift, r.solve_ms, r.setup_ms, r.res_ms, r.jac_ms, r.lu_ms, r.steps);
  }
  std::fflush(stdout);
}

// --refresh: what one kernel-parameter change costs a population (Population::configure with the parameter moved,
// which rebuilds every table), and inside a run (rates() after the change, less rates() without), best and median of
// R rounds of 200 changes each, in microseconds per change, three times over.
// Populations: the headline bed's (glass-transition aggregation, Vogel-Peukert breakage, water carried, folded; 10 and
// 40 classes from 50 to 1000 um) changing ln beta0, and the constant kernel on 100 classes (25 doublings, q = 4) for
// both aggregation schemes changing beta0. Compare builds by running them alternately.
int refresh_bench(int repeats) {
  // The mechanisms as a unit's settings name them (the headline bed's choices, units/fluid_bed.cpp), and the
  // properties carried.
  struct Setup {
    std::string label;
    std::shared_ptr<const kernels::Grid> grid;
    std::map<std::string, std::string> settings;
    std::vector<std::string> properties;
  };
  auto headline = [](int n) {
    std::vector<double> d(n);
    for (int i = 0; i < n; ++i) d[i] = 50e-6 * std::pow(1000.0 / 50.0, double(i) / (n - 1));
    return Setup{"headline glass_transition+breakage n=" + std::to_string(n),
                 std::make_shared<const kernels::Grid>(kernels::Grid::from_diameter_pivots(d)),
                 {{"aggregation", "glass_transition"},
                  {"aggregation_scheme", "fixed_pivot"},
                  {"breakage", "vogel_peukert"},
                  {"fragments", "tanh_power_law"},
                  {"breakage_scheme", "fixed_pivot"},
                  {"outside", "fold"}},
                 {"water"}};
  };
  auto constant = [](const std::string& scheme) {
    return Setup{"constant " + scheme + " n=100",
                 std::make_shared<const kernels::Grid>(kernels::Grid::geometric(std::exp2(-12.0), 4, 100)),
                 {{"aggregation", "constant"}, {"aggregation_scheme", scheme}},
                 {}};
  };
  for (const Setup& c : {headline(10), headline(40), constant("fixed_pivot"), constant("cell_average")}) {
    UnitSpec spec;
    Settings st("bench", c.settings);
    kernels::PopulationOptions options;
    options.properties = c.properties;
    kernels::Population pop;
    pop.declare(spec, st, c.grid, options);
    std::vector<double> p;
    for (const auto& ps : spec.params()) p.push_back(ps.value);
    auto w = pop.make_work();
    pop.configure(*w, p.data(), "bench");
    const double p0 = p[0];
    // An evaluation at an empty state (every class 0, fields at mid-range values): its cost with the parameter moved
    // less its cost without is what a change costs inside a run (rates() refreshes the tables itself).
    const int n = c.grid->size(), P = static_cast<int>(c.properties.size());
    std::vector<double> zeros(n, 0.0), floor(n, 1e-9), fields[kernels::kFields], out(size_t(n) * (1 + P) + 64, 0.0);
    const double field_values[kernels::kFields] = {0.01, 0.1, 320.0, 0.01, 0.5};
    kernels::Population::State<double> es;
    kernels::Population::Rates<double> rt;
    es.N = zeros.data(), es.floor = floor.data(), es.p = p.data(), rt.dN = out.data(), rt.outside = out.data() + n;
    for (int f = 0; f < kernels::kFields; ++f) fields[f].assign(n, field_values[f]), es.fields[f] = fields[f].data();
    for (int k = 0; k < P; ++k) es.q[k] = zeros.data(), rt.dq[k] = out.data() + size_t(n) * (1 + k);
    rt.outside = out.data() + size_t(n) * (1 + P);
    constexpr int kChanges = 200;
    auto per_change = [&](auto&& step) {  // best and median of `repeats` rounds, us per step
      std::vector<double> rounds;
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = clk::now();
        for (int k = 0; k < kChanges; ++k) step(k);
        rounds.push_back(ms_since(t0) * 1e3 / kChanges);
      }
      std::sort(rounds.begin(), rounds.end());
      return std::make_pair(rounds.front(), rounds[rounds.size() / 2]);
    };
    auto move = [&](int k) { p[0] = k % 2 ? p0 : p0 * 1.001 + 1e-3; };  // the aggregation kernel's first parameter
    for (int round = 0; round < 3; ++round) {
      const auto conf = per_change([&](int k) { move(k), pop.configure(*w, p.data(), "bench"); });
      const auto changed = per_change([&](int k) { move(k), pop.rates(*w, es, rt); });
      p[0] = p0;
      const auto same = per_change([&](int) { pop.rates(*w, es, rt); });
      std::printf(
          "%-44s %-9s configure best %8.3f median %8.3f us | rates after a change %8.3f (%8.3f), without "
          "%8.3f (%8.3f): change %8.3f us\n",
          c.label.c_str(), pop.aggregation_evaluation(*w).c_str(), conf.first, conf.second, changed.first,
          changed.second, same.first, same.second, changed.first - same.first);
    }
  }
  return 0;
}

// --jacobian: the Jacobian and the residual of pbm_batch (aggregation only, q = 4 on the verification grid) at a state
// of the constant kernel's run, best and median of R rounds of 20 calls, in microseconds per call.
int jacobian_bench(int repeats) {
  for (const char* kernel : {"constant", "sum"})
    for (const char* scheme : {"fixed_pivot", "cell_average"}) {
      auto s = pbm_test::grid_settings(4, 27);
      s["aggregation"] = kernel, s["aggregation_scheme"] = scheme;
      auto fs = pbm_test::flowsheet(s);
      DaeSystem sys(*fs);
      const int n = sys.size();
      std::vector<double> y(n), yp(n, 0.0), r(n), J(size_t(n) * n);
      sys.initial_values(y);
      for (int i = 0; i < n; ++i) y[i] = std::abs(y[i]) * (0.5 + 0.5 * std::sin(0.7 * i) * std::sin(0.7 * i)) + 1e-6;
      auto best_median = [&](auto&& call) {
        std::vector<double> rounds;
        for (int k = 0; k < repeats; ++k) {
          const auto t0 = clk::now();
          for (int c = 0; c < 20; ++c) call();
          rounds.push_back(ms_since(t0) * 1e3 / 20);
        }
        std::sort(rounds.begin(), rounds.end());
        return std::make_pair(rounds.front(), rounds[rounds.size() / 2]);
      };
      const auto jac = best_median([&] { sys.jacobian(0, y.data(), yp.data(), 10.0, J.data(), nullptr); });
      const auto res = best_median([&] { sys.residual(0, y.data(), yp.data(), r.data()); });
      std::printf("%-9s %-13s n=%3d  jacobian best %9.2f median %9.2f us   residual best %7.2f median %7.2f us\n",
                  kernel, scheme, n, jac.first, jac.second, res.first, res.second);
    }
  return 0;
}

}  // namespace
}  // namespace granuflow

int main(int argc, char** argv) {
  using namespace granuflow;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--refresh") {
      int r = 50;
      for (int k = 1; k + 1 < argc; ++k)
        if (std::string(argv[k]) == "--repeats") r = std::max(1, std::atoi(argv[k + 1]));
      return refresh_bench(r);
    } else if (std::string(argv[i]) == "--jacobian") {
      int r = 30;
      for (int k = 1; k + 1 < argc; ++k)
        if (std::string(argv[k]) == "--repeats") r = std::max(1, std::atoi(argv[k + 1]));
      return jacobian_bench(r);
    }
  bool json = false, quick = false;
  int repeats = 5;
  std::string only, scheme;
  int only_q = 0;
  double only_rtol = 0;
  std::vector<std::string> integrators;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--json")
      json = true;
    else if (a == "--quick")
      quick = true;
    else if (a == "--repeats" && i + 1 < argc) {
      char* end = nullptr;
      const long r = std::strtol(argv[++i], &end, 10);
      if (end == argv[i] || *end != '\0' || r < 1 || r > 100000) {
        std::fprintf(stderr, "granuflow_bench_pbm: --repeats '%s': not a whole number from 1 to 100000\n", argv[i]);
        return 2;
      }
      repeats = static_cast<int>(r);
    } else if (a == "--case" && i + 1 < argc)
      only = argv[++i];
    else if ((a == "--q" || a == "--rtol") && i + 1 < argc) {
      char* end = nullptr;
      const double v = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !(v > 0)) {  // a value matching no grid is refused below
        std::fprintf(stderr, "granuflow_bench_pbm: %s '%s': not a positive number\n", a.c_str(), argv[i]);
        return 2;
      }
      if (a == "--q")
        only_q = v == std::floor(v) ? static_cast<int>(v) : -1;  // -1: selects no grid
      else
        only_rtol = v;
    } else if (a == "--scheme" && i + 1 < argc)
      scheme = argv[++i];
    else if (a == "--integrators" && i + 1 < argc) {
      integrators.clear();
      std::string list = argv[++i];
      for (size_t p = 0; p <= list.size();) {
        const size_t e = std::min(list.find(',', p), list.size());
        if (e > p) integrators.push_back(list.substr(p, e - p));
        p = e + 1;
      }
    } else {
      std::fprintf(stderr,
                   "usage: granuflow_bench_pbm [--json] [--repeats R] [--quick] [--case NAME] "
                   "[--integrators auto,ida,bdf,adams,erk] [--q Q] [--rtol R] [--scheme NAME]\n");
      return 2;
    }
  }
  const std::vector<std::string> agg{"cell_average", "fixed_pivot"};
  const std::vector<Case> cases{{"constant", 100.0, 27, agg},
                                {"sum", 3.0, 27, agg},
                                {"product", 0.4, 27, agg},
                                {"growth", 1.0, 19, {"fv_koren", "fv_upwind"}},
                                {"breakage", 10.0, 27, agg}};
  const std::vector<int> qs = quick ? std::vector<int>{1, 2, 4} : std::vector<int>{1, 2, 3, 4, 6, 8, 12};
  const std::vector<double> rtols =
      quick ? std::vector<double>{1e-2, 1e-4, 1e-6} : std::vector<double>{1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  if (integrators.empty())
    integrators = quick ? std::vector<std::string>{"auto", "ida", "adams", "erk"}
                        : std::vector<std::string>{"auto", "ida", "bdf", "adams", "erk"};
  // The filters select among the runs; one that selects none is an error, not an empty benchmark.
  auto selected = [&](const Case& c, const std::string& m, int q, double rtol) {
    return (only.empty() || c.name == only) && (scheme.empty() || m == scheme) && (!only_q || q == only_q) &&
           (!only_rtol || rtol == only_rtol);
  };
  size_t count = 0;
  for (const auto& c : cases)
    for (const auto& m : c.methods)
      for (int q : qs)
        for (double rtol : rtols) count += selected(c, m, q, rtol);
  if (count == 0) {
    std::fprintf(stderr,
                 "granuflow_bench_pbm: --case/--scheme/--q/--rtol select no run (cases constant, sum, product, growth, "
                 "breakage; schemes cell_average, fixed_pivot, fv_koren, fv_upwind; q in {%s}; rtol in {%s})\n",
                 quick ? "1, 2, 4" : "1, 2, 3, 4, 6, 8, 12", quick ? "1e-2, 1e-4, 1e-6" : "1e-2, 1e-3, ..., 1e-8");
    return 2;
  }
  for (const auto& integrator : integrators)
    if (integrator != "auto" && integrator != "ida" && integrator != "bdf" && integrator != "adams" &&
        integrator != "erk") {
      std::fprintf(stderr, "granuflow_bench_pbm: --integrators '%s': not one of auto, ida, bdf, adams, erk\n",
                   integrator.c_str());
      return 2;
    }
  const std::string meta = meta_json();
  for (const auto& c : cases)
    for (const auto& m : c.methods)
      for (const auto& integrator : integrators)
        for (int q : qs)
          for (double rtol : rtols)
            if (selected(c, m, q, rtol)) print(run(c, m, integrator, q, rtol, repeats), json, repeats, meta);
  return 0;
}
