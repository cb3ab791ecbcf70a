// Measured particle size distributions (sieve analyses, laser diffraction, image analysis) and their mapping onto a
// size Grid; docs/measured_psd.md describes the formats.
//
// A table is sizes d_k (m, strictly increasing) and values y_k of one kind and one basis:
//   * kind Q (cumulative undersize): y_k = Q(d_k); nondecreasing, the last value is the total (1 or 100 %);
//   * kind retained (sieve analysis): y_k = amount retained on the sieve of mesh d_k, i.e. in [d_k, d_{k+1});
//     the top sieve's class ends at d_last^2 / d_{last-1} (the same size ratio); a first row of size 0 is the pan;
//   * kind q (density per unit size): y_k = q over the class [d_k, d_{k+1}) (per m in SI; per the size column's
//     unit in a file); the last row closes the last class and its value must be 0;
//   * basis mass or volume (one solid density: the same fractions, Q3/q3) or number (Q0/q0).
// Every kind is first turned into Q at the knots d_k, interpolated linearly in ln d between knots (the amount of a
// class spread uniformly over ln d, as psd.hpp reads d50 back from a grid), 0 below the first knot, 1 above the
// last; what lies below the first knot (Q(d_0) > 0, the pan) is taken to lie just below it.
//
// Mapping onto a grid of edges e_0 < ... < e_n: the amount of cell i is Q(e_{i+1}) - Q(e_i), so the cells hold
// exactly Q(e_n) - Q(e_0) (the in-grid fraction); the measured amount below e_0 and above e_n is reported and folded
// into the first and last cell (as the log-normal initial beds fold their tails), so the total is conserved.
// Mass basis: the cells' mass fractions are exact. Number basis: the cells' number fractions are exact and the mass
// fractions follow with the pivot volumes, m_i ~ n_i x_i (the mass within a cell is not known from a number table
// beyond the cell's pivot).
#pragma once
#include <string>
#include <vector>

#include "discretization/grid.hpp"

namespace granuflow::kernels {

enum class PsdBasis { kMass, kVolume, kNumber };
enum class PsdKind { kRetained, kCumulative, kDensity };
std::string to_string(PsdBasis b);                     // mass | volume | number
std::string to_string(PsdKind k);                      // retained | Q | q
PsdBasis psd_basis_from_string(const std::string& s);  // ConfigError listing the choices
PsdKind psd_kind_from_string(const std::string& s);    // ConfigError listing the choices

struct MeasuredPsd {
  std::vector<double> sizes;   // m
  std::vector<double> values;  // as given (fractions or %); kind q: per m
  PsdBasis basis = PsdBasis::kMass;
  PsdKind kind = PsdKind::kCumulative;
  std::string source;        // the file, or a name, for messages
  std::vector<int> rows;     // the file's line of each entry (1-based), or the array index + 1
  std::string value_column;  // for messages ("Q3", "retained" ...)
};

// Checks a table: at least two rows, finite non-negative values, sizes strictly increasing (> 0, but a pan of size
// 0 first for retained), Q nondecreasing, q's last value 0, total 1 or 100 (within 0.5 % of it). Every problem is
// one ConfigError "<source>: row R, column C: ... value ...".
void check_measured_psd(const MeasuredPsd& t);
// From arrays (Python): sizes in m, q in 1/m; checked. Rows are the array indices + 1 in messages.
MeasuredPsd make_measured_psd(std::vector<double> sizes_m, std::vector<double> values, PsdBasis basis, PsdKind kind,
                              const std::string& source);
// Parses a CSV file's text: '#' comments and blank lines skipped, a UTF-8 BOM accepted; a header naming a size column
// (size_m, size_mm, size_um) and one value column: Q3 | Q0 | q3 | q0 (volume / number basis) | retained (mass) |
// Q_mass | q_mass | retained_number | retained_volume. Checked.
MeasuredPsd parse_measured_psd(const std::string& text, const std::string& path);
MeasuredPsd read_measured_psd(const std::string& path);

// The table's cumulative distribution (0..1) at its knots: Q[k] = Q(d[k]).
struct Cumulative {
  std::vector<double> d, Q;
  double at(double size) const;  // Q(size), linear in ln d between knots
};
Cumulative cumulative(const MeasuredPsd& t);

struct GridPsd {
  std::vector<double> mass;    // mass fraction of each cell (outside folded into the end cells), sums to 1
  std::vector<double> number;  // number basis: number fraction of each cell (folded likewise); else empty
  double below = 0.0;          // fraction of the measured amount (in the table's basis) below the grid's first edge
  double above = 0.0;          // ... above its last edge
  double outside() const { return below + above; }
};
GridPsd map_to_grid(const MeasuredPsd& t, const Grid& g);

// Process-wide named tables (from Python), selected by a unit setting; same rules as data_tables.hpp.
void set_measured_psd(const std::string& name, MeasuredPsd t);
const MeasuredPsd& measured_psd(const std::string& name);  // ConfigError listing the loaded names
std::vector<std::string> measured_psd_names();

}  // namespace granuflow::kernels
