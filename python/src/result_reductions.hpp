// The reductions of a run's time series that granuflow.result.Result and the sweep batch share: one implementation,
// reading the (time x column) block in place wherever it lives (a SimResult's vector, a NumPy array, the core's own
// result arrays), so that a plain run never needs NumPy to write its summary and files. Each reduction keeps the order
// of floating-point operations NumPy used when Result computed it, so the numbers in summary.json did not move.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace granuflow::python {

// A strided (rows x cols) view of doubles; strides in bytes, as the buffer protocol gives them.
struct BlockView {
  const char* base = nullptr;
  std::ptrdiff_t rows = 0, cols = 0, row_stride = 0, col_stride = 0;
  double operator()(std::ptrdiff_t k, std::ptrdiff_t j) const {
    return *reinterpret_cast<const double*>(base + k * row_stride + j * col_stride);
  }
  static BlockView dense(const std::vector<double>& v, std::ptrdiff_t rows, std::ptrdiff_t cols) {
    return {reinterpret_cast<const char*>(v.data()), rows, cols, cols * std::ptrdiff_t(sizeof(double)),
            std::ptrdiff_t(sizeof(double))};
  }
};

// np.max of one column: NaN wins.
double column_max(const BlockView& b, std::ptrdiff_t j);

// np.array_equal of column i of a and column j of b (-0.0 equals 0.0, NaN equals nothing).
bool columns_equal(const BlockView& a, std::ptrdiff_t i, const BlockView& b, std::ptrdiff_t j);

// The mass fraction of each of `ends` (positions in `mass_cols`) among the columns `mass_cols` at every row, as
// Result.grid_ends had NumPy compute it (m = outputs[:, mass_cols]; total = m.sum(axis=1); the fraction 0 where the
// total is not positive): {first row, last row, max over rows (NaN wins)} per end.
std::vector<std::array<double, 3>> end_fractions(const BlockView& b, const std::vector<std::ptrdiff_t>& mass_cols,
                                                 const std::vector<std::ptrdiff_t>& ends);

}  // namespace granuflow::python
