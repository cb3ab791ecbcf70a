// Named numeric tables that kernels read data from (DEM collision frequencies, measured kernels): loaded once
// by the caller (a scene loader, Python, a test) before the flowsheet is built, and selected by name in a unit
// setting, so a scene says "agg_collisions: gf25_run3" and never a number. Process-wide; not for concurrent
// writes while flowsheets are being built.
#pragma once
#include <string>
#include <vector>

namespace granuflow::kernels {

struct Table {
  int rows = 0;
  int cols = 0;
  std::vector<double> values;  // row-major
  std::string unit;            // SI unit of the values
  std::string source;          // where the numbers come from
  double at(int r, int c) const { return values[size_t(r) * cols + c]; }
};

// Throws ConfigError when rows * cols does not match the values or a value is not finite.
void set_table(const std::string& name, Table table);
// Throws ConfigError listing the loaded tables when `name` is unknown.
const Table& table(const std::string& name);
std::vector<std::string> table_names();

}  // namespace granuflow::kernels
