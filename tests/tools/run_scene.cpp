// granuflow_run_scene SCENE [t_end_s] [--repeat N] [--linear-solver NAME] [--method NAME]: load a scene and run it
// through the C++ core, printing the summary values at the end. Exit 0 on success, 2 on bad input (ConfigError), 3
// on solver failure, as the CLI does.
//
// With --repeat N the run is repeated and the best wall time printed with the solver statistics: a profiler (perf)
// then sees the core with its symbols, which the stripped Python module hides.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"
#include "granuflow/simulator.hpp"
#include "units/registry.hpp"

namespace {
// The whole argument as a number, or false (no silent 0 from "abc", no 3 from "3x").
bool parse(const char* a, double& v) {
  char* end = nullptr;
  v = std::strtod(a, &end);
  return end != a && *end == '\0' && std::isfinite(v);
}
}  // namespace

int main(int argc, char** argv) {
  using namespace granuflow;
  const char* usage =
      "usage: granuflow_run_scene SCENE [t_end_s] [--repeat N] [--linear-solver dense|sparse|gmres|auto] "
      "[--method auto|ida|bdf|adams|erk]\n";
  std::string path, linear_solver, method;
  double t_end = -1.0, repeats = 1.0;
  bool ok = true;
  for (int i = 1; i < argc && ok; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc) {
      ok = parse(argv[++i], repeats) && repeats >= 1 && repeats == std::floor(repeats) && repeats <= 1e6;
    } else if (a == "--linear-solver" && i + 1 < argc) {
      linear_solver = argv[++i];
    } else if (a == "--method" && i + 1 < argc) {
      method = argv[++i];
    } else if (path.empty() && a.rfind("--", 0) != 0) {
      path = a;
    } else if (t_end < 0 && a.rfind("--", 0) != 0) {
      ok = parse(argv[i], t_end) && t_end > 0;
    } else {
      ok = false;
    }
    if (!ok) std::fprintf(stderr, "granuflow_run_scene: '%s' (argument %d): not allowed here\n", argv[i], i);
  }
  if (!ok || path.empty()) {
    std::fprintf(stderr, "%s  t_end_s > 0 (s); N a whole number >= 1\n", usage);
    return 2;
  }
  const int repeat = static_cast<int>(repeats);
  try {
    Scene s = load_scene(path, units::builtin());
    if (t_end > 0) s.options.t_end = t_end, s.options.t_out.clear();
    if (!linear_solver.empty()) s.options.linear_solver = parse_linear_solver(linear_solver, "--linear-solver");
    if (!method.empty()) s.options.method = parse_method(method, "--method");
    SimResult r;
    double best = 1e300;
    for (int k = 0; k < repeat; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      r = simulate(*s.flowsheet, s.options);
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    const auto states = s.flowsheet->state_names();
    const auto outputs = r.output_names;
    const size_t last = r.t.size() - 1;
    std::printf("%s: t = %g s, %zu steps\n", s.name.c_str(), r.t[last], size_t(r.stats.steps));
    if (repeat > 1)
      std::printf("  best of %d: %.3f ms; %ld residuals, %ld Jacobians, %ld linear setups; %s, %s\n", repeat,
                  best * 1e3, long(r.stats.residuals), long(r.stats.jacobians), long(r.stats.linear_setups),
                  r.stats.method.c_str(), r.stats.linear_solver.c_str());
    for (const auto& [key, src] : s.summary) {
      double v = 0.0;
      bool found = false;
      for (size_t k = 0; k < states.size() && !found; ++k)
        if (states[k] == src) v = r.state(last, static_cast<int>(k)), found = true;
      for (size_t k = 0; k < outputs.size() && !found; ++k)
        if (outputs[k] == src) v = r.outputs[last * outputs.size() + k], found = true;
      std::printf("  %s = %.6g\n", key.c_str(), v);
    }
    return 0;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "granuflow_run_scene: bad input: %s\n", e.what());
    return 2;
  } catch (const SolverError& e) {
    std::fprintf(stderr, "granuflow_run_scene: solver failure: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "granuflow_run_scene: %s\n", e.what());
    return 1;
  }
}
