// Builds and runs a one-unit flowsheet with pbm_batch for the PBM tests.
#pragma once
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/simulator.hpp"
#include "kernels/discretization/grid.hpp"
#include "units/registry.hpp"

namespace granuflow::pbm_test {

using Strings = std::map<std::string, std::string>;
using Values = std::map<std::string, double>;

// The grid settings (grid, q, v_min, classes, d_min, d_max) go to the particle system, the rest to pbm_batch.
inline std::unique_ptr<Flowsheet> flowsheet(const Strings& settings, const Values& params = {}) {
  auto fs = std::make_unique<Flowsheet>("pbm");
  Strings grid{{"grid", "geometric"}}, unit;
  for (const auto& [k, v] : settings)
    (k == "grid" || k == "q" || k == "v_min" || k == "classes" || k == "d_min" || k == "d_max" ? grid : unit)[k] = v;
  fs->add_unit("particles", units::builtin().create("particles"), Settings("particles", grid));
  fs->add_unit("pbm", units::builtin().create("pbm_batch"), Settings("pbm", unit));
  fs->finalize();
  // "rho": the particles' envelope density (solid without pores)
  for (const auto& [k, v] : params)
    if (k == "rho")
      fs->set_param("particles.rho_s", v), fs->set_param("particles.eps_intra", 0.0);
    else
      fs->set_param("pbm." + k, v);
  return fs;
}

// The verification grid: v from 2^-12 to 2^15 (27 doublings), q classes per doubling.
inline Strings grid_settings(int q, int doublings = 27) {
  return {{"q", std::to_string(q)}, {"classes", std::to_string(doublings * q)}};
}
inline kernels::Grid grid(int q, int doublings = 27) {
  return kernels::Grid::geometric(std::exp2(-12.0), q, doublings * q);
}

// Position of `name` in `names`; a quantity that is not there (renamed, or not declared for these mechanisms) throws,
// so a test fails instead of reading a silent 0.
inline size_t index_of(const std::vector<std::string>& names, const std::string& name) {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return i;
  throw std::out_of_range("no quantity '" + name + "' in this run");
}

struct Run {
  SimResult result;
  int n = 0;
  const double* N(size_t k) const { return &result.y[k * result.state_names.size()]; }
  double state(size_t k, const std::string& name) const {
    return result.y[k * result.state_names.size() + index_of(result.state_names, "pbm." + name)];
  }
  // Book-keeping states exist only for the mechanisms that fill them (volume_below: breakage or growth; ...): an
  // absent one holds nothing.
  double state_or_zero(size_t k, const std::string& name) const {
    for (const auto& s : result.state_names)
      if (s == "pbm." + name) return state(k, name);
    return 0.0;
  }
  double output(size_t k, const std::string& name) const {
    return result.outputs[k * result.output_names.size() + index_of(result.output_names, "pbm." + name)];
  }
};

inline Run run(Flowsheet& fs, std::vector<double> t_out, double rtol = 1e-8, double atol = 1e-12,
               const std::string& method = "auto") {
  SimOptions o;
  o.method = parse_method(method);
  o.t_end = t_out.back();
  o.t_out = std::move(t_out);
  o.rtol = rtol;
  o.atol = atol;
  Run r;
  r.result = simulate(fs, o);
  for (const auto& s : r.result.state_names)
    if (s.rfind("pbm.N_", 0) == 0) ++r.n;
  return r;
}

inline double moment(const kernels::Grid& g, const double* N, int k) {
  double s = 0;
  for (int i = 0; i < g.size(); ++i) s += N[i] * std::pow(g.pivot(i), k);
  return s;
}

}  // namespace granuflow::pbm_test
