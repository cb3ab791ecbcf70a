// granuflow_run_scene SCENE [t_end_s]: load a scene and run it through the C++ core, printing the summary
// values at the end. Exit 0 on success, 2 on bad input (ConfigError), 3 on solver failure, as the CLI does.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"
#include "granuflow/simulator.hpp"
#include "units/registry.hpp"

int main(int argc, char** argv) {
  using namespace granuflow;
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: granuflow_run_scene SCENE [t_end_s]\n");
    return 2;
  }
  try {
    Scene s = load_scene(argv[1], units::builtin());
    if (argc == 3) s.options.t_end = std::atof(argv[2]), s.options.t_out.clear();
    const SimResult r = simulate(*s.flowsheet, s.options);
    const auto states = s.flowsheet->state_names();
    const auto outputs = r.output_names;
    const size_t last = r.t.size() - 1;
    std::printf("%s: t = %g s, %zu steps\n", s.name.c_str(), r.t[last], size_t(r.stats.steps));
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
  }
}
