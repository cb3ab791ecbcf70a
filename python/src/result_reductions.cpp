// See result_reductions.hpp.
#include "result_reductions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace granuflow::python {
namespace {

// NumPy's pairwise summation of a contiguous run of doubles (its sum of a single row).
double pairwise_sum(const double* a, size_t n) {
  if (n < 8) {
    double r = 0.0;
    for (size_t i = 0; i < n; ++i) r += a[i];
    return r;
  }
  if (n <= 128) {
    double r[8];
    for (int j = 0; j < 8; ++j) r[j] = a[j];
    size_t i = 8;
    for (; i < n - (n % 8); i += 8)
      for (int j = 0; j < 8; ++j) r[j] += a[i + j];
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) res += a[i];
    return res;
  }
  size_t n2 = n / 2;
  n2 -= n2 % 8;
  return pairwise_sum(a, n2) + pairwise_sum(a + n2, n - n2);
}

double max_nan(const std::vector<double>& x) {
  double m = x[0];
  for (size_t k = 1; k < x.size(); ++k) {
    if (std::isnan(x[k]) || std::isnan(m)) return std::numeric_limits<double>::quiet_NaN();
    m = std::max(m, x[k]);
  }
  return m;
}

}  // namespace

double column_max(const BlockView& b, std::ptrdiff_t j) {
  double m = b(0, j);
  for (std::ptrdiff_t k = 1; k < b.rows; ++k) {
    const double v = b(k, j);
    if (std::isnan(v) || std::isnan(m)) return std::numeric_limits<double>::quiet_NaN();
    m = std::max(m, v);
  }
  return m;
}

bool columns_equal(const BlockView& a, std::ptrdiff_t i, const BlockView& b, std::ptrdiff_t j) {
  if (a.rows != b.rows) return false;
  for (std::ptrdiff_t k = 0; k < a.rows; ++k)
    if (!(a(k, i) == b(k, j))) return false;
  return true;
}

std::vector<std::array<double, 3>> end_fractions(const BlockView& b, const std::vector<std::ptrdiff_t>& mass_cols,
                                                 const std::vector<std::ptrdiff_t>& ends) {
  const auto nt = static_cast<size_t>(b.rows);
  // NumPy's copy outputs[:, mass_cols] is summed along its rows pairwise when it has one row, and class by class
  // (a Fortran-ordered copy) when it has several.
  std::vector<double> total(nt), row(mass_cols.size());
  for (size_t k = 0; k < nt; ++k) {
    for (size_t c = 0; c < mass_cols.size(); ++c) row[c] = b(k, mass_cols[c]);
    if (nt == 1) {
      total[k] = pairwise_sum(row.data(), row.size());
    } else {
      double s = 0.0;
      for (double x : row) s += x;
      total[k] = s;
    }
  }
  std::vector<std::array<double, 3>> out;
  std::vector<double> f(nt);
  for (std::ptrdiff_t e : ends) {
    for (size_t k = 0; k < nt; ++k) f[k] = total[k] > 0 ? b(k, mass_cols[e]) / total[k] : 0.0;
    out.push_back({f[0], f[nt - 1], max_nan(f)});
  }
  return out;
}

}  // namespace granuflow::python
