#include "data_tables.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {
namespace {
std::map<std::string, Table>& store() {
  static std::map<std::string, Table> tables;
  return tables;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

bool is_file(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// One line of a collision file: its number in the file and its fields.
struct Line {
  int row = 0;
  std::vector<std::string> fields;
};
}  // namespace

void set_table(const std::string& name, Table t) {
  if (t.rows < 1 || t.cols < 1 || t.values.size() != size_t(t.rows) * t.cols)
    throw ConfigError("table '" + name + "': " + std::to_string(t.values.size()) + " values for " +
                      std::to_string(t.rows) + " x " + std::to_string(t.cols));
  for (double v : t.values)
    if (!std::isfinite(v)) throw ConfigError(violation("table '" + name + "' value", v, t.unit, "finite"));
  store()[name] = std::move(t);
}

const Table& table(const std::string& name) {
  auto it = store().find(name);
  if (it != store().end()) return it->second;
  std::string names;
  for (const auto& [k, v] : store()) names += (names.empty() ? "" : ", ") + k;
  throw ConfigError("unknown data table '" + name + "' (loaded: " + (names.empty() ? "none" : names) + ")");
}

std::vector<std::string> table_names() {
  std::vector<std::string> v;
  for (const auto& [k, t] : store()) v.push_back(k);
  return v;
}

int CollisionCounts::class_of(double d) const {
  if (edges.empty() || d < edges.front() || d > edges.back()) return -1;
  if (d == edges.back()) return classes() - 1;
  return static_cast<int>(std::upper_bound(edges.begin(), edges.end(), d) - edges.begin()) - 1;
}

namespace {
constexpr const char* kCollisionKeys = "like_collisions, dt_s, edges_m, particles, counts";

// A collision file's rows: the single rows dt_s, edges_m and particles by key, and the counts rows in order.
struct CollisionRows {
  std::string path;
  std::map<std::string, Line> single;
  std::vector<Line> counts;
  ConfigError fail(int row, int col, const std::string& what) const {
    return ConfigError(path + ": row " + std::to_string(row) + (col > 0 ? ", column " + std::to_string(col) : "") +
                       ": " + what);
  }
  // Field k of line l as a finite number.
  double number(const Line& l, size_t k) const {
    const std::string& f = l.fields[k];
    char* end = nullptr;
    errno = 0;
    const double v = f.empty() ? NAN : std::strtod(f.c_str(), &end);
    if (f.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
      throw fail(l.row, static_cast<int>(k) + 1, "'" + shown(f) + "' is not a finite number");
    return v;
  }
};

CollisionRows collision_rows(const std::string& text, const std::string& path) {
  CollisionRows r;
  r.path = path;
  // A byte-order mark (as spreadsheet programs write UTF-8 CSV) is no part of the first key.
  const bool bom = text.compare(0, 3, "\xEF\xBB\xBF") == 0;
  std::istringstream in(bom ? text.substr(3) : text);
  std::string raw;
  int row = 0;
  while (std::getline(in, raw)) {
    ++row;
    const std::string s = trim(raw.substr(0, raw.find('#')));
    if (s.empty()) continue;
    Line line{row, {}};
    std::string field;
    std::istringstream fs(s);
    while (std::getline(fs, field, ',')) line.fields.push_back(trim(field));
    if (s.back() == ',') line.fields.emplace_back();
    const std::string key = line.fields.front();
    if (key == "counts") {
      r.counts.push_back(std::move(line));
    } else if (key == "dt_s" || key == "edges_m" || key == "particles" || key == "like_collisions") {
      if (r.single.count(key))
        throw r.fail(row, 1, "'" + key + "' given twice (first on row " + std::to_string(r.single[key].row) + ")");
      r.single[key] = std::move(line);
    } else {
      throw r.fail(row, 1, "unknown key '" + shown(key) + "' (expected one of " + kCollisionKeys + ")");
    }
  }
  for (const char* key : {"dt_s", "edges_m", "particles"})
    if (!r.single.count(key))
      throw ConfigError(path + ": no '" + key + "' row (a collision file has the rows " + kCollisionKeys +
                        "; docs/dem_collisions.md)");
  if (r.counts.empty()) throw ConfigError(path + ": no 'counts' rows (one per class; docs/dem_collisions.md)");
  return r;
}

// The counting window, the class edges and the particle numbers.
void read_classes(CollisionRows& r, CollisionCounts& c) {
  const Line& dt = r.single["dt_s"];
  if (dt.fields.size() != 2)
    throw r.fail(dt.row, 0,
                 "dt_s takes one value (the counting window in s), got " + std::to_string(dt.fields.size() - 1));
  c.dt = r.number(dt, 1);
  if (!(c.dt > 0)) throw r.fail(dt.row, 2, "dt_s = " + fmt_num(c.dt) + " s: the counting window must be > 0");

  const Line& ed = r.single["edges_m"];
  if (ed.fields.size() < 3)
    throw r.fail(
        ed.row, 0,
        "edges_m needs at least two class edges (diameters in m), got " + std::to_string(ed.fields.size() - 1));
  for (size_t k = 1; k < ed.fields.size(); ++k) {
    const double e = r.number(ed, k);
    if (!(e > 0)) throw r.fail(ed.row, static_cast<int>(k) + 1, "edge " + fmt_num(e) + " m: diameters must be > 0");
    if (!c.edges.empty() && !(e > c.edges.back()))
      throw r.fail(ed.row, static_cast<int>(k) + 1,
                   "edge " + fmt_num(e) + " m after " + fmt_num(c.edges.back()) + " m: edges must increase");
    c.edges.push_back(e);
  }
  const size_t n = c.edges.size() - 1;

  const Line& pa = r.single["particles"];
  if (pa.fields.size() != n + 1)
    throw r.fail(pa.row, 0,
                 std::to_string(pa.fields.size() - 1) + " particle numbers for " + std::to_string(n) +
                     " classes (edges_m on row " + std::to_string(ed.row) + " gives " + std::to_string(n + 1) +
                     " edges)");
  for (size_t k = 1; k <= n; ++k) {
    const double f = r.number(pa, k);
    if (!(f >= 0))
      throw r.fail(pa.row, static_cast<int>(k) + 1, "particles " + fmt_num(f) + ": a particle number must be >= 0");
    c.particles.push_back(f);
  }
}

// The n x n counts: one row per class, symmetric, none for a class without particles.
void read_counts(CollisionRows& r, CollisionCounts& c) {
  const size_t n = c.edges.size() - 1;
  const std::vector<Line>& count_rows = r.counts;
  if (count_rows.size() != n)
    throw r.fail(count_rows.back().row, 0,
                 std::to_string(count_rows.size()) + " 'counts' rows for " + std::to_string(n) +
                     " classes (one row per class, edges_m on row " + std::to_string(r.single["edges_m"].row) + ")");
  c.counts.assign(n * n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const Line& l = count_rows[i];
    if (l.fields.size() != n + 1)
      throw r.fail(l.row, 0,
                   std::to_string(l.fields.size() - 1) + " counts for " + std::to_string(n) + " classes (class " +
                       std::to_string(i + 1) + "'s row of the n x n matrix)");
    for (size_t j = 0; j < n; ++j) {
      const double v = r.number(l, j + 1);
      if (!(v >= 0))
        throw r.fail(l.row, static_cast<int>(j) + 2, "count " + fmt_num(v) + ": collision counts must be >= 0");
      c.counts[i * n + j] = v;
    }
  }
  const int pa_row = r.single["particles"].row;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j) {
      const double a = c.counts[i * n + j], b = c.counts[j * n + i];
      if (j > i && std::abs(a - b) > 1e-9 * std::max(std::abs(a), std::abs(b)))
        throw r.fail(count_rows[i].row, static_cast<int>(j) + 2,
                     "count " + fmt_num(a) + " for classes " + std::to_string(i + 1) + " x " + std::to_string(j + 1) +
                         " differs from " + fmt_num(b) + " on row " + std::to_string(count_rows[j].row) + ", column " +
                         std::to_string(i + 2) + ": the matrix must be symmetric");
      if (a > 0 && (c.particles[i] == 0 || c.particles[j] == 0)) {
        const size_t e = c.particles[i] == 0 ? i : j;
        throw r.fail(count_rows[i].row, static_cast<int>(j) + 2,
                     "count " + fmt_num(a) + " for classes " + std::to_string(i + 1) + " x " + std::to_string(j + 1) +
                         ", but class " + std::to_string(e + 1) + " has no particles (row " + std::to_string(pa_row) +
                         ", column " + std::to_string(e + 2) + ")");
      }
    }
}
// How the file counts a collision of two particles of one class: the diagonal of Eq. (12) differs by a factor of
// two between the readings and no default is safe, so a file must say (docs/dem_collisions.md).
void read_like_collisions(CollisionRows& r, CollisionCounts& c) {
  const auto it = r.single.find("like_collisions");
  if (it == r.single.end())
    throw ConfigError(r.path +
                      ": no 'like_collisions' row: say how a collision of two particles of one class is counted in "
                      "N_ii, 'like_collisions,twice' (once by each partner) or 'like_collisions,once' "
                      "(docs/dem_collisions.md)");
  const Line& l = it->second;
  const std::string v = l.fields.size() == 2 ? l.fields[1] : std::string();
  if (v != "twice" && v != "once")
    throw r.fail(l.row, 2,
                 "like_collisions takes one value, 'twice' or 'once' (got '" +
                     shown(l.fields.size() > 1 ? l.fields[1] : std::string()) + (l.fields.size() > 2 ? "', ..." : "'") +
                     ")");
  c.like_tally = v == "twice" ? 2 : 1;
}
}  // namespace

CollisionCounts parse_collision_counts(const std::string& text, const std::string& path) {
  CollisionRows rows = collision_rows(text, path);
  CollisionCounts c;
  c.path = path;
  read_classes(rows, c);
  read_counts(rows, c);
  read_like_collisions(rows, c);
  // Eq. (12) of paper 002 must give a number: counts near the largest double over particle numbers near the smallest
  const size_t n = c.particles.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j)
      if (c.particles[i] > 0 && c.particles[j] > 0 &&
          !std::isfinite(c.counts[i * n + j] * (i == j ? 2.0 / c.like_tally : 1.0) /
                         (c.particles[i] * c.particles[j] * c.dt)))
        throw rows.fail(rows.counts[i].row, static_cast<int>(j) + 2,
                        "count " + fmt_num(c.counts[i * n + j]) +
                            ": the collision frequency count / (F_i F_j dt) of Eq. (12) is not a finite number");
  return c;
}

CollisionCounts read_collision_counts(const std::string& path) {
  if (!is_file(path)) throw ConfigError(path + ": cannot open the collision file (no such file)");
  std::ifstream f(path);
  if (!f) throw ConfigError(path + ": cannot open the collision file");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_collision_counts(ss.str(), path);
}

std::string resolve_data_path(const std::string& where, const std::string& file) {
  if (file.empty() || file.front() == '/') return file;
  const auto colon = where.find(": ");
  if (colon == std::string::npos) return file;
  // A label may carry a note after the scene's path ("scene.yaml (grid refined 2x)", a refined copy for the error
  // estimate): the file is the part before it, so the copy reads the data the scene reads from any working folder.
  for (std::string label = where.substr(0, colon);;) {
    if (is_file(label)) {
      const auto slash = label.find_last_of('/');
      return (slash == std::string::npos ? std::string(".") : label.substr(0, slash)) + "/" + file;
    }
    const auto note = label.rfind(" (");
    if (note == std::string::npos) return file;
    label.erase(note);
  }
}

}  // namespace granuflow::kernels
