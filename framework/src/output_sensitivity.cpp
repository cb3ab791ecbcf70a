#include "granuflow/output_sensitivity.hpp"

#include "granuflow/errors.hpp"

namespace granuflow {

std::vector<double> output_sensitivities(const Flowsheet& fs, const SimResult& r) {
  const size_t nt = r.t.size(), np = r.sens_params.size(), ns = r.state_names.size(), no = r.output_names.size();
  if (np == 0 || r.sens.size() != nt * np * ns)
    throw ConfigError(
        "output_sensitivities: the simulation result carries no state sensitivities "
        "(run simulate() with SimOptions.sensitivities)");
  if (static_cast<int>(ns) != fs.n_states() || static_cast<int>(no) != fs.n_outputs())
    throw ConfigError("output_sensitivities: the simulation result does not belong to flowsheet '" + fs.name() + "'");
  if (r.output_sens.size() != nt * np * no)
    throw std::logic_error("output_sensitivities: simulate() recorded no output sensitivities");
  return r.output_sens;
}

}  // namespace granuflow
