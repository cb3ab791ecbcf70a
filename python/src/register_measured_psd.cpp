// Measured size distributions from Python (kernels/discretization/measured_psd.hpp): check a table given as arrays,
// read a CSV file, evaluate its cumulative distribution, map it onto size-grid edges, and set it by name for the
// units' setting initial_psd_table (or psd_table of a solids feed). A table crosses as a dict of sizes_m, values,
// basis, kind, source; every check is the C++ one, so Python and scenes refuse the same tables with the same line.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"
#include "kernels/discretization/measured_psd.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

using kernels::MeasuredPsd;

MeasuredPsd from_args(const std::vector<double>& sizes, const std::vector<double>& values, const std::string& basis,
                      const std::string& kind, const std::string& source) {
  return kernels::make_measured_psd(sizes, values, kernels::psd_basis_from_string(basis),
                                    kernels::psd_kind_from_string(kind), source);
}

py::dict to_dict(const MeasuredPsd& t) {
  return py::dict("sizes_m"_a = t.sizes, "values"_a = t.values, "basis"_a = kernels::to_string(t.basis),
                  "kind"_a = kernels::to_string(t.kind), "source"_a = t.source);
}

}  // namespace

void register_measured_psd(py::module_& m) {
  m.def(
      "measured_psd_check",
      [](const std::vector<double>& s, const std::vector<double>& v, const std::string& basis, const std::string& kind,
         const std::string& source) { return to_dict(from_args(s, v, basis, kind, source)); },
      "sizes_m"_a, "values"_a, "basis"_a, "kind"_a, "source"_a);
  m.def(
      "read_measured_psd", [](const std::string& path) { return to_dict(kernels::read_measured_psd(path)); }, "path"_a);
  m.def(
      "measured_psd_cumulative",
      [](const std::vector<double>& s, const std::vector<double>& v, const std::string& basis, const std::string& kind,
         const std::string& source, const std::vector<double>& at) {
        const kernels::Cumulative c = kernels::cumulative(from_args(s, v, basis, kind, source));
        std::vector<double> q;
        for (double d : at) q.push_back(c.at(d));
        return q;
      },
      "sizes_m"_a, "values"_a, "basis"_a, "kind"_a, "source"_a, "at_m"_a);
  m.def(
      "measured_psd_map",
      [](const std::vector<double>& s, const std::vector<double>& v, const std::string& basis, const std::string& kind,
         const std::string& source, const std::vector<double>& diameter_edges) {
        std::vector<double> ve;
        for (double d : diameter_edges) {
          if (!(d > 0)) throw ConfigError(violation("grid diameter edge", d, "m", "edge > 0"));
          ve.push_back(kernels::volume_of_diameter(d));
        }
        const kernels::Grid g = kernels::Grid::from_edges(ve);
        const kernels::GridPsd r = kernels::map_to_grid(from_args(s, v, basis, kind, source), g);
        return py::dict("mass"_a = r.mass, "number"_a = r.number, "below"_a = r.below, "above"_a = r.above,
                        "pivots_m"_a = g.diameter_pivots());
      },
      "sizes_m"_a, "values"_a, "basis"_a, "kind"_a, "source"_a, "diameter_edges_m"_a);
  m.def(
      "set_measured_psd",
      [](const std::string& name, const std::vector<double>& s, const std::vector<double>& v, const std::string& basis,
         const std::string& kind,
         const std::string& source) { kernels::set_measured_psd(name, from_args(s, v, basis, kind, source)); },
      "name"_a, "sizes_m"_a, "values"_a, "basis"_a, "kind"_a, "source"_a);
  m.def("measured_psd_names", &kernels::measured_psd_names);
  m.def(
      "unit_size_edges",
      [](const Scene& s, const std::string& unit) {
        for (const auto& u : s.flowsheet->units())
          if (u.name == unit) return u.spec.size_edges();
        throw ConfigError("no unit '" + unit + "' in flowsheet '" + s.flowsheet->name() + "'");
      },
      "scene"_a, "unit"_a);
}

}  // namespace granuflow::python
