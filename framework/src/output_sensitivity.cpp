#include "granuflow/output_sensitivity.hpp"

#include <algorithm>
#include <cmath>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"

namespace granuflow {

void OutputSensitivityOptions::validate() const {
  if (!(rel_step > 0 && rel_step < 0.1))
    throw ConfigError(violation("OutputSensitivityOptions.rel_step", rel_step, "", "0 < rel_step < 0.1"));
}

std::vector<double> output_sensitivities(Flowsheet& fs, const SimResult& r, const OutputSensitivityOptions& opt) {
  opt.validate();
  const size_t nt = r.t.size(), np = r.sens_params.size(), ns = r.state_names.size(), no = r.output_names.size();
  if (np == 0 || r.sens.size() != nt * np * ns)
    throw ConfigError(
        "output_sensitivities: the simulation result carries no state sensitivities "
        "(run simulate() with SimOptions.sensitivities)");
  if (static_cast<int>(ns) != fs.n_states() || static_cast<int>(no) != fs.n_outputs())
    throw ConfigError("output_sensitivities: the simulation result does not belong to flowsheet '" + fs.name() + "'");
  std::vector<double> dz(nt * np * no, 0.0);
  if (no == 0 || nt == 0) return dz;

  DaeSystem sys(fs, /*inline_explicit=*/false);  // report() works on full state vectors either way
  const double t_end = *std::max_element(r.t.begin(), r.t.end());
  const std::vector<double> breaks = fs.breakpoints(t_end);
  // The segment an output time belongs to, as simulate() recorded it (a breakpoint closes its segment).
  auto segment_start = [&](double t) {
    double s = 0.0;
    for (double b : breaks)
      if (b < t) s = b;
    return s;
  };
  std::vector<double> scale(ns);
  for (size_t i = 0; i < ns; ++i) scale[i] = fs.state_spec(static_cast<int>(i)).scale;

  std::vector<double> y(ns), zp(no), zm(no);
  for (size_t it = 0; it < nt; ++it) {
    const double t = r.t[it];
    sys.set_segment_start(segment_start(t));
    const double* y0 = &r.y[it * ns];
    const double* yp0 = &r.yp[it * ns];
    for (size_t k = 0; k < np; ++k) {
      const double* s = &r.sens[(it * np + k) * ns];
      // Step h along s such that no state moves by more than rel_step of its magnitude.
      double smax = 0.0;
      for (size_t i = 0; i < ns; ++i) smax = std::max(smax, std::abs(s[i]) / (std::abs(y0[i]) + scale[i]));
      if (!(smax > 0) || !std::isfinite(smax)) continue;
      const double h = opt.rel_step / smax;
      for (size_t i = 0; i < ns; ++i) y[i] = y0[i] + h * s[i];
      sys.report(t, y.data(), yp0, zp.data());
      for (size_t i = 0; i < ns; ++i) y[i] = y0[i] - h * s[i];
      sys.report(t, y.data(), yp0, zm.data());
      double* out = &dz[(it * np + k) * no];
      for (size_t j = 0; j < no; ++j) out[j] = (zp[j] - zm[j]) / (2 * h);
    }
  }

  // Direct dependence of report() on the parameters (at fixed states).
  for (size_t k = 0; k < np; ++k) {
    const int id = fs.param_id(r.sens_params[k]);
    const double p = fs.param_value(id);
    const ParamSpec& spec = fs.param_spec(id);
    const double h = opt.rel_step * std::max(std::abs(p), 1e-12);
    const double hi = std::min(p + h, spec.upper), lo = std::max(p - h, spec.lower);
    if (!(hi > lo)) continue;
    std::vector<double> zhi(nt * no), zlo(nt * no);
    try {
      for (int side = 0; side < 2; ++side) {
        fs.set_param_value(id, side == 0 ? hi : lo);
        sys.reconfigure();
        for (size_t it = 0; it < nt; ++it) {
          sys.set_segment_start(segment_start(r.t[it]));
          sys.report(r.t[it], &r.y[it * ns], &r.yp[it * ns], (side == 0 ? zhi : zlo).data() + it * no);
        }
      }
    } catch (...) {  // the caller's flowsheet keeps its parameter value whatever a unit throws
      fs.set_param_value(id, p);
      sys.reconfigure();
      throw;
    }
    fs.set_param_value(id, p);
    for (size_t it = 0; it < nt; ++it)
      for (size_t j = 0; j < no; ++j) {
        const double d = (zhi[it * no + j] - zlo[it * no + j]) / (hi - lo);
        if (std::isfinite(d)) dz[(it * np + k) * no + j] += d;
      }
  }
  sys.reconfigure();  // units configured with the unperturbed parameters again
  return dz;
}

}  // namespace granuflow
