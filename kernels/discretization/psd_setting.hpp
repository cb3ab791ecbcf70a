// The size distribution a unit starts from (its initial bed) or feeds: the log-normal of its own parameters (the
// default), or a measured table (measured_psd.hpp) named in the unit's settings:
//   <prefix>psd: lognormal | table
//   <prefix>psd_file: CSV file, relative to the scene file's folder (docs/measured_psd.md)
//   <prefix>psd_table: name of a table set from Python (granuflow.set_measured_psd), when no file is given
#pragma once
#include <string>

#include "discretization/measured_psd.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow::kernels {

struct TablePsd {
  bool table = false;  // false: the unit's log-normal
  GridPsd psd;         // the table mapped on the unit's grid
  std::string source;  // file or table name
  double d50 = 0.0;    // m, the mapped distribution's mass median (a reference size for tolerances)
};

// Reads the settings; with a table, reads and maps it (ConfigError naming the setting, then the file's own message).
// `what` names the distribution in the settings' descriptions ("initial bed", "feed").
TablePsd declare_table_psd(Settings& st, const Grid& g, const std::string& prefix, const std::string& what);
// The table settings alone (<prefix>psd_file, <prefix>psd_table), for a unit that chooses the table otherwise.
TablePsd read_table_psd(Settings& st, const Grid& g, const std::string& prefix, const std::string& what);

}  // namespace granuflow::kernels
