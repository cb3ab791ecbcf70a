#include "size_fraction.hpp"

#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/quantity.hpp"

namespace granuflow::calib {

std::optional<SizeFraction> size_fraction(const Flowsheet& fs, const std::string& name) {
  const auto dot = name.find(".Q3(");
  if (dot == std::string::npos || name.back() != ')') return std::nullopt;
  SizeFraction f;
  f.unit = name.substr(0, dot);
  const std::string text = name.substr(dot + 4, name.size() - dot - 5);
  const std::string where = "observable '" + name + "'";
  double v = 0.0;
  std::string u;
  if (!parse_quantity(text, &v, &u))
    throw ConfigError(where + ": size '" + shown(text) + "' is not a length (e.g. bed.Q3(500 um))");
  f.size = to_si(v, u, "m", where);
  if (!(f.size > 0) || !std::isfinite(f.size))
    throw ConfigError(violation(where + ": size", f.size, "m", "0 < size < inf"));
  const auto outs = fs.output_names();
  for (const auto& inst : fs.units()) {
    if (inst.name != f.unit) continue;
    const auto& d = inst.spec.size_edges();
    if (d.empty())
      throw ConfigError(where + ": unit '" + f.unit + "' reports no size distribution with class edges (a fluid_bed " +
                        "or particle chamber does)");
    const std::string m0 = f.unit + ".psd_m_0";
    for (size_t k = 0; k < outs.size(); ++k)
      if (outs[k] == m0) f.first_output = static_cast<int>(k);
    const int n = static_cast<int>(d.size()) - 1;
    f.w.assign(n, 0.0);
    for (int i = 0; i < n; ++i)
      f.w[i] = f.size >= d[i + 1] ? 1.0 : f.size <= d[i] ? 0.0 : std::log(f.size / d[i]) / std::log(d[i + 1] / d[i]);
    return f;
  }
  throw ConfigError(where + ": no unit '" + f.unit + "' in flowsheet '" + fs.name() + "'");
}

double size_fraction_value(const SizeFraction& f, const double* m, double* dq) {
  const size_t n = f.w.size();
  double total = 0.0, below = 0.0;
  for (size_t i = 0; i < n; ++i)
    if (m[i] > 0) total += m[i], below += f.w[i] * m[i];
  if (!(total > 0)) {
    if (dq)
      for (size_t i = 0; i < n; ++i) dq[i] = 0.0;
    return std::nan("");  // an empty population has no distribution
  }
  const double q = below / total;
  if (dq)
    for (size_t i = 0; i < n; ++i) dq[i] = m[i] > 0 ? (f.w[i] - q) / total : 0.0;
  return q;
}

}  // namespace granuflow::calib
