// Named numeric tables that kernels read data from (DEM collision frequencies, measured kernels): loaded once
// by the caller (a scene loader, Python, a test) before the flowsheet is built, and selected by name in a unit
// setting, so a scene says "agg_collisions: gf25_run3" and never a number. Process-wide; not for concurrent
// writes while flowsheets are being built.
//
// DEM collision counts (paper 002, Eq. (12)) come as a file the user brings from their DEM run: the format is
// described in docs/dem_collisions.md, read_collision_counts() checks it line by line and names the file, row and
// column of anything it cannot accept.
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

// Collisions counted in a DEM run between particles of n size classes during a window of length dt.
struct CollisionCounts {
  std::string path;               // the file, for messages
  double dt = 0.0;                // s, length of the counting window
  std::vector<double> edges;      // m, n + 1 increasing class edges in particle diameter
  std::vector<double> particles;  // F_i, particles of class i in the window (time average), n
  std::vector<double> counts;     // N_coll,ij, n x n row-major, symmetric
  int like_tally = 2;             // times a collision within one class appears in N_ii (file key like_collisions)
  int classes() const { return static_cast<int>(particles.size()); }
  // Class holding diameter d (m): edges[c] <= d < edges[c + 1]; the last edge belongs to the last class; -1 outside.
  int class_of(double d) const;
};

// Parses the text of a collision-count file (docs/dem_collisions.md). Every problem is a ConfigError
// "<path>: row R, column C: ..." (rows are the file's lines, columns its comma-separated fields, both from 1).
CollisionCounts parse_collision_counts(const std::string& text, const std::string& path);
// Reads and parses `path`; ConfigError when it cannot be opened.
CollisionCounts read_collision_counts(const std::string& path);

// A data file named in a unit setting: absolute paths as given, relative ones from the folder of the scene file
// the setting came from (the label before ": " in Settings::where(), when that is a file, or its part before a note
// in parentheses), else from the working folder.
std::string resolve_data_path(const std::string& settings_where, const std::string& file);

}  // namespace granuflow::kernels
