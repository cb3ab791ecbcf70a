#include "discretization/psd_setting.hpp"

#include "data_tables.hpp"
#include "discretization/psd.hpp"
#include "granuflow/errors.hpp"

namespace granuflow::kernels {

TablePsd declare_table_psd(Settings& st, const Grid& g, const std::string& prefix, const std::string& what) {
  const bool table =
      st.get_choice(prefix + "psd", "lognormal", {"lognormal", "table"},
                    "size distribution of the " + what +
                        ": lognormal (the parameters) or table (a measured distribution, docs/measured_psd.md)") ==
      "table";
  return table ? read_table_psd(st, g, prefix, what) : TablePsd{};
}

TablePsd read_table_psd(Settings& st, const Grid& g, const std::string& prefix, const std::string& what) {
  TablePsd r;
  r.table = true;
  const std::string file =
      st.get_choice(prefix + "psd_file", "", {},
                    "CSV of the measured " + what + " size distribution; relative to the scene's folder");
  std::string name;
  if (file.empty()) {
    auto names = measured_psd_names();
    if (names.empty())
      throw ConfigError(st.where() + "." + prefix + "psd_file: not given, and no measured size distribution is " +
                        "loaded from Python; name the CSV file of the " + what + " (docs/measured_psd.md)");
    name = st.get_choice(prefix + "psd_table", names.front(), names,
                         "measured size distribution set from Python, used when no " + prefix + "psd_file is given");
  }
  try {
    const MeasuredPsd t = file.empty() ? measured_psd(name) : read_measured_psd(resolve_data_path(st.where(), file));
    r.psd = map_to_grid(t, g);
    r.source = t.source;
  } catch (const ConfigError& e) {
    throw ConfigError(st.where() + "." + prefix + (file.empty() ? "psd_table = '" + name : "psd_file = '" + file) +
                      "': " + e.what());
  }
  r.d50 = characteristic_diameter_of_mass(g.diameter_edges(), r.psd.mass.data(), 0.5);
  return r;
}

}  // namespace granuflow::kernels
