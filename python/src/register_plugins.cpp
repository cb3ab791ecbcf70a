// Plugins from Python: load a library of units and kernels, list what is loaded and where each registered name came
// from (granuflow/plugin.hpp).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "granuflow/build_info.hpp"
#include "granuflow/plugin.hpp"
#include "kernels/registry.hpp"
#include "units/registry.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace granuflow::python {
namespace {

template <class Base>
void add_origins(py::dict& out, const char* family, const Registry<Base>& reg) {
  py::dict d;
  for (const auto& n : reg.names())
    if (!reg.origin(n).empty()) d[py::str(n)] = reg.origin(n);
  out[family] = d;
}

py::dict plugin_origins() {
  py::dict out;
  add_origins(out, "units", units::builtin());
  kernels::registries().for_each([&](const char* family, const auto& reg) { add_origins(out, family, reg); });
  return out;
}

}  // namespace

void register_plugins(py::module_& m) {
  m.def("load_plugin", &load_plugin, "path"_a,
        "Load a plugin library and run its registration; returns its real path (ConfigError when it is none).");
  m.def("load_plugin_path", &load_plugin_path, "search_path"_a,
        "Load every plugin of a ':'-separated list of folders (their *.so files) and files.");
  m.def("loaded_plugins", &loaded_plugins, "Real paths of the plugins loaded, in order.");
  m.def("plugin_abi_tag", &plugin_abi_tag, "The version and ABI tag a plugin must carry to be loaded.");
  m.def("build_isa", &build_isa, "Instruction set of the loaded core (x86-64, x86-64-v3, ... or native).");
  m.def("loaded_core_libraries", &loaded_core_libraries, "Paths of the libgranuflow_* libraries this process loaded.");
  m.def("plugin_origins", &plugin_origins, "Per family, the names plugins registered and the file of each.");
}

}  // namespace granuflow::python
