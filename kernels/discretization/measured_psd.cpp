#include "discretization/measured_psd.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

std::string to_string(PsdBasis b) {
  return b == PsdBasis::kMass ? "mass" : b == PsdBasis::kVolume ? "volume" : "number";
}
std::string to_string(PsdKind k) {
  return k == PsdKind::kRetained ? "retained" : k == PsdKind::kCumulative ? "Q" : "q";
}
PsdBasis psd_basis_from_string(const std::string& s) {
  for (PsdBasis b : {PsdBasis::kMass, PsdBasis::kVolume, PsdBasis::kNumber})
    if (to_string(b) == s) return b;
  throw ConfigError("size distribution basis '" + shown(s) + "': not one of mass, volume, number");
}
PsdKind psd_kind_from_string(const std::string& s) {
  for (PsdKind k : {PsdKind::kRetained, PsdKind::kCumulative, PsdKind::kDensity})
    if (to_string(k) == s) return k;
  throw ConfigError("size distribution kind '" + shown(s) + "': not one of retained, Q, q");
}

namespace {
constexpr double kTotalTolerance = 0.005;  // a total within 0.5 % of 1 or 100 % is accepted (and renormalized)

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// "<source>: row R, column C (name): what"; the size column is 1, the value column 2.
ConfigError fail(const MeasuredPsd& t, size_t k, int col, const std::string& what) {
  const int row = k < t.rows.size() ? t.rows[k] : static_cast<int>(k) + 1;
  const std::string name = col == 1 ? "size" : t.value_column;
  return ConfigError(t.source + ": row " + std::to_string(row) + ", column " + std::to_string(col) + " (" + name +
                     "): " + what);
}

double total_of(const MeasuredPsd& t) {
  const auto& y = t.values;
  if (t.kind == PsdKind::kCumulative) return y.back();
  double s = 0.0;
  for (size_t k = 0; k < y.size(); ++k)
    s += t.kind == PsdKind::kRetained ? y[k] : k + 1 < y.size() ? y[k] * (t.sizes[k + 1] - t.sizes[k]) : 0.0;
  return s;
}
}  // namespace

void check_measured_psd(const MeasuredPsd& t) {
  const auto &d = t.sizes, &y = t.values;
  const size_t n = d.size();
  if (y.size() != n)
    throw ConfigError(t.source + ": " + std::to_string(n) + " sizes but " + std::to_string(y.size()) + " values");
  const bool pan = t.kind == PsdKind::kRetained && n > 0 && d[0] == 0.0;
  if (n < 2u + (pan ? 1u : 0u))
    throw ConfigError(t.source + ": " + std::to_string(n) + " rows; a size distribution needs at least two sizes" +
                      (pan ? " besides the pan" : ""));
  for (size_t k = 0; k < n; ++k) {
    if (!std::isfinite(d[k])) throw fail(t, k, 1, "size " + fmt_num(d[k]) + " is not a finite number");
    if (!std::isfinite(y[k])) throw fail(t, k, 2, "value " + fmt_num(y[k]) + " is not a finite number");
    if (y[k] < 0) throw fail(t, k, 2, "value " + fmt_num(y[k]) + " is negative");
    if (k == 0 && !(d[0] > 0) && !pan)
      throw fail(
          t, k, 1,
          "size " + fmt_num(d[0]) + " is not positive (a size 0 is allowed only as the pan of a retained table)");
    if (k > 0 && !(d[k] > d[k - 1]))
      throw fail(t, k, 1, "size " + fmt_num(d[k]) + " m does not increase (previous " + fmt_num(d[k - 1]) + " m)");
    if (k > 0 && t.kind == PsdKind::kCumulative && y[k] < y[k - 1])
      throw fail(t, k, 2, "Q decreases from " + fmt_num(y[k - 1]) + " to " + fmt_num(y[k]));
  }
  if (t.kind == PsdKind::kDensity && y[n - 1] != 0.0)
    throw fail(t, n - 1, 2,
               "value " + fmt_num(y[n - 1]) +
                   ": the last row of a density q only closes the last class, its value "
                   "must be 0");
  const double total = total_of(t);
  const bool one = std::abs(total - 1.0) <= kTotalTolerance, hundred = std::abs(total - 100.0) <= 100 * kTotalTolerance;
  if (!one && !hundred) {
    const std::string what = t.kind == PsdKind::kCumulative ? "the last Q"
                             : t.kind == PsdKind::kRetained ? "the sum of the retained amounts"
                                                            : "the integral of q over the classes";
    throw fail(t, n - 1, 2,
               what + " is " + fmt_num(total) + ": neither 1 nor 100 % (within 0.5 %); give fractions or percentages");
  }
}

MeasuredPsd make_measured_psd(std::vector<double> sizes_m, std::vector<double> values, PsdBasis basis, PsdKind kind,
                              const std::string& source) {
  MeasuredPsd t;
  t.sizes = std::move(sizes_m), t.values = std::move(values), t.basis = basis, t.kind = kind, t.source = source;
  t.value_column = kind == PsdKind::kRetained ? "retained" : kind == PsdKind::kCumulative ? "Q" : "q";
  check_measured_psd(t);
  return t;
}

MeasuredPsd parse_measured_psd(const std::string& text_in, const std::string& path) {
  std::string text = text_in;
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  MeasuredPsd t;
  t.source = path;
  std::istringstream in(text);
  std::string line;
  double scale = 0.0;  // m per unit of the size column
  for (int row = 1; std::getline(in, line); ++row) {
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ls(s);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(trim(x));
    if (f.size() != 2)
      throw ConfigError(path + ": row " + std::to_string(row) + ": " + std::to_string(f.size()) +
                        " columns; expected two, a size and a value column (docs/measured_psd.md)");
    if (scale == 0.0) {  // the header
      static const std::map<std::string, double> sizes = {
          {"size_m", 1.0}, {"size_mm", 1e-3}, {"size_um", 1e-6}, {"size_\xC2\xB5m", 1e-6}};
      static const std::map<std::string, std::pair<PsdKind, PsdBasis>> columns = {
          {"Q3", {PsdKind::kCumulative, PsdBasis::kVolume}},
          {"Q0", {PsdKind::kCumulative, PsdBasis::kNumber}},
          {"q3", {PsdKind::kDensity, PsdBasis::kVolume}},
          {"q0", {PsdKind::kDensity, PsdBasis::kNumber}},
          {"retained", {PsdKind::kRetained, PsdBasis::kMass}},
          {"Q_mass", {PsdKind::kCumulative, PsdBasis::kMass}},
          {"q_mass", {PsdKind::kDensity, PsdBasis::kMass}},
          {"retained_number", {PsdKind::kRetained, PsdBasis::kNumber}},
          {"retained_volume", {PsdKind::kRetained, PsdBasis::kVolume}}};
      auto is = sizes.find(f[0]);
      if (is == sizes.end())
        throw ConfigError(path + ": row " + std::to_string(row) + ", column 1: header '" + shown(f[0]) +
                          "': not a size column (size_m, size_mm, size_um)");
      auto ic = columns.find(f[1]);
      if (ic == columns.end())
        throw ConfigError(path + ": row " + std::to_string(row) + ", column 2: header '" + shown(f[1]) +
                          "': not a value column (Q3, Q0, q3, q0, retained, Q_mass, q_mass, retained_number, "
                          "retained_volume)");
      scale = is->second;
      t.value_column = f[1];
      std::tie(t.kind, t.basis) = ic->second;
      continue;
    }
    double v[2];
    for (int c = 0; c < 2; ++c) {
      char* end = nullptr;
      v[c] = std::strtod(f[c].c_str(), &end);
      if (f[c].empty() || *end != '\0')
        throw ConfigError(path + ": row " + std::to_string(row) + ", column " + std::to_string(c + 1) + " (" +
                          (c == 0 ? std::string("size") : t.value_column) + "): '" + shown(f[c]) + "' is not a number");
    }
    t.sizes.push_back(v[0] * scale);
    t.values.push_back(t.kind == PsdKind::kDensity ? v[1] / scale : v[1]);  // q per m
    t.rows.push_back(row);
  }
  if (scale == 0.0) throw ConfigError(path + ": no header (a size column and a value column, docs/measured_psd.md)");
  check_measured_psd(t);
  return t;
}

MeasuredPsd read_measured_psd(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw ConfigError(path + ": cannot open the size-distribution file");
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_measured_psd(ss.str(), path);
}

double Cumulative::at(double size) const {
  if (!(size >= d.front())) return 0.0;
  if (size >= d.back()) return Q.back();
  size_t k = 0;
  while (d[k + 1] <= size) ++k;
  return Q[k] + (Q[k + 1] - Q[k]) * std::log(size / d[k]) / std::log(d[k + 1] / d[k]);
}

Cumulative cumulative(const MeasuredPsd& t) {
  const auto &d = t.sizes, &y = t.values;
  const size_t n = d.size();
  const double total = total_of(t);
  Cumulative c;
  if (t.kind == PsdKind::kCumulative) {
    c.d = d;
    for (double v : y) c.Q.push_back(v / total);
  } else if (t.kind == PsdKind::kDensity) {
    c.d = d;
    c.Q.push_back(0.0);
    for (size_t k = 0; k + 1 < n; ++k) c.Q.push_back(c.Q.back() + y[k] * (d[k + 1] - d[k]) / total);
  } else {
    const size_t first = d[0] == 0.0 ? 1 : 0;  // the pan lies below the first sieve
    double below = first ? y[0] : 0.0;
    for (size_t k = first; k < n; ++k) {
      c.d.push_back(d[k]);
      c.Q.push_back(below / total);
      below += y[k];
    }
    c.d.push_back(d[n - 1] * d[n - 1] / d[n - 2]);  // the top sieve's class: the same size ratio
    c.Q.push_back(1.0);
  }
  c.Q.back() = 1.0;  // the total is the normalization
  return c;
}

GridPsd map_to_grid(const MeasuredPsd& t, const Grid& g) {
  const Cumulative c = cumulative(t);
  const auto& de = g.diameter_edges();
  const int n = g.size();
  std::vector<double> q(n + 1);
  for (int i = 0; i <= n; ++i) q[i] = c.at(de[i]);
  GridPsd r;
  r.below = q[0], r.above = 1.0 - q[n];
  std::vector<double> f(n);
  for (int i = 0; i < n; ++i) f[i] = q[i + 1] - q[i];
  f[0] += r.below, f[n - 1] += r.above;  // folded: the total amount stays that of the table
  if (t.basis != PsdBasis::kNumber) {
    r.mass = f;
    return r;
  }
  r.number = f;
  double m = 0.0;
  for (int i = 0; i < n; ++i) m += f[i] * g.pivot(i);
  r.mass.resize(n);
  for (int i = 0; i < n; ++i) r.mass[i] = f[i] * g.pivot(i) / m;
  return r;
}

namespace {
std::map<std::string, MeasuredPsd>& store() {
  static std::map<std::string, MeasuredPsd> s;
  return s;
}
}  // namespace

void set_measured_psd(const std::string& name, MeasuredPsd t) {
  check_measured_psd(t);
  store()[name] = std::move(t);
}

const MeasuredPsd& measured_psd(const std::string& name) {
  auto it = store().find(name);
  if (it != store().end()) return it->second;
  std::string names;
  for (const auto& [k, v] : store()) names += (names.empty() ? "" : ", ") + k;
  throw ConfigError("unknown measured size distribution '" + shown(name) +
                    "' (loaded: " + (names.empty() ? "none" : names) + ")");
}

std::vector<std::string> measured_psd_names() {
  std::vector<std::string> v;
  for (const auto& [k, t] : store()) v.push_back(k);
  return v;
}

}  // namespace granuflow::kernels
