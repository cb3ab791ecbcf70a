// The constant-volume Monte Carlo of agglomeration from Python (montecarlo/, docs/monte_carlo.md): its declaration
// (parameters and settings, for describe and the docs) and a run, which releases the GIL while its replicas run.
// Results cross as a dict of flat lists that granuflow.montecarlo shapes into arrays.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <map>
#include <string>
#include <vector>

#include "interrupt_poll.hpp"
#include "mc_params.hpp"
#include "mc_statistics.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {

void register_montecarlo(py::module_& m) {
  namespace mc = granuflow::montecarlo;
  m.def("montecarlo_params", [] {
    py::list out;
    for (const ParamSpec& p : mc::param_specs())
      out.append(py::dict("name"_a = p.name, "unit"_a = p.unit, "default"_a = p.value, "lower"_a = p.lower,
                          "upper"_a = p.upper, "description"_a = p.description, "source"_a = p.source));
    return out;
  });
  m.def("montecarlo_settings", [] {
    py::list out;
    for (const SettingSpec& s : mc::setting_specs())
      out.append(py::dict("name"_a = s.name, "type"_a = to_string(s.type), "default"_a = setting_to_string(s.value),
                          "choices"_a = s.choices, "lower"_a = s.lower, "upper"_a = s.upper,
                          "description"_a = s.description));
    return out;
  });
  m.def(
      "montecarlo_run",
      [](const std::map<std::string, double>& params, const std::map<std::string, std::string>& settings,
         const std::vector<double>& times) {
        const mc::Config c = mc::make_config(params, settings);
        mc::Summary s;
        {
          const CoreCall call;
          s = mc::run(c, times);
        }
        py::dict derived("f_coll"_a = c.d.f_coll, "gamma"_a = c.d.gamma, "h0"_a = c.d.h0, "k_dry"_a = c.d.k_dry,
                         "k_imb"_a = c.d.k_imb, "t_life"_a = c.d.t_life, "droplet_volume"_a = c.d.V_drop,
                         "primary_mass"_a = c.d.m0);
        return py::dict("times"_a = s.times, "replicas"_a = s.replicas, "quantities"_a = mc::quantity_names(),
                        "psd_bins"_a = mc::kPsdBins, "mean"_a = s.mean, "lo"_a = s.lo, "hi"_a = s.hi,
                        "psd_mean"_a = s.psd_mean, "psd_lo"_a = s.psd_lo, "psd_hi"_a = s.psd_hi,
                        "per_replica"_a = s.per_replica, "events"_a = s.events, "collisions"_a = s.collisions,
                        "successes"_a = s.successes, "depositions"_a = s.depositions, "events_per_s"_a = s.events_per_s,
                        "bytes_per_particle"_a = s.bytes_per_particle,
                        "bytes_per_agglomerate"_a = s.bytes_per_agglomerate,
                        "bytes_per_droplet"_a = s.bytes_per_droplet, "wall_s"_a = s.wall_s,
                        "doublings_mean"_a = s.doublings_mean, "threads"_a = s.threads, "derived"_a = derived);
      },
      "params"_a, "settings"_a, "times"_a);
}

}  // namespace granuflow::python
