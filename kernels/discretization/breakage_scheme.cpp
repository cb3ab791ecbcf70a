#include "discretization/breakage_scheme.hpp"

#include <algorithm>

namespace granuflow::kernels {
namespace {

enum class Segments { kPivotIntervals, kCells, kCellMass };

template <class T>
void build_matrix(const Grid& g, const FragmentDistribution& f, const T* p, T* A, Segments seg) {
  const int n = g.size();
  std::fill(A, A + size_t(n + kOutsideRows) * n, T(0.0));
  std::vector<T> col(n + kOutsideRows);
  for (int k = 0; k < n; ++k) {
    const double u = g.pivot(k);
    const T norm = 1.0 / f.cumulative(u, u, p);
    std::fill(col.begin(), col.end(), T(0.0));
    // Segment [lo, hi] of the fragment volumes: its number and volume per broken parent.
    auto packet = [&](double lo, double hi, T& number, T& volume) {
      number = f.number(lo, hi, u, p) * norm;
      volume = u * (f.cumulative(hi, u, p) - f.cumulative(lo, u, p)) * norm;
    };
    T number, volume;
    if (seg == Segments::kPivotIntervals) {
      col[n + kVolumeBelow] += u * f.cumulative(g.lower_virtual(), u, p) * norm;
      for (int a = -1; a < k; ++a) {
        packet(g.pivot_ext(a), g.pivot(a + 1), number, volume);
        split_between(g, a, number, volume, col.data());
      }
    } else if (seg == Segments::kCellMass) {
      // The mass of the fragments in each cell (the parent's own cell up to its pivot), placed on the cell's pivot:
      // volume is kept, number is not. Fines below the first edge go to the first class.
      T below(0.0);
      for (int c = 0; c <= k; ++c) {
        const T b = f.cumulative(c == k ? u : g.edge(c + 1), u, p) * norm;
        col[c] += (b - below) * (u / g.pivot(c));
        below = b;
      }
    } else {
      col[n + kVolumeBelow] += u * f.cumulative(g.edge(0), u, p) * norm;
      for (int i = 0; i <= k; ++i) {
        packet(g.edge(i), std::min(g.edge(i + 1), u), number, volume);
        split_between(g, volume >= g.pivot(i) * number ? i : i - 1, number, volume, col.data());
      }
    }
    col[k] -= 1.0;  // the parent
    for (int r = 0; r < n + kOutsideRows; ++r) A[size_t(r) * n + k] = col[r];
  }
}

}  // namespace

void BreakageScheme::matrix(const Grid& g, const FragmentDistribution& f, const double* p, int count,
                            std::vector<double>& A) const {
  std::vector<double> key(p, p + count);
  A.resize(size_t(g.size() + kOutsideRows) * g.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (valid_ && key_ == key) {
      A = A_;
      return;
    }
  }
  build(g, f, p, A.data());
  std::lock_guard<std::mutex> lock(mutex_);
  key_ = std::move(key);
  A_ = A;
  valid_ = true;
}

void CellMassBreakage::build(const Grid& g, const FragmentDistribution& f, const double* p, double* A) const {
  build_matrix(g, f, p, A, Segments::kCellMass);
}
void CellMassBreakage::build(const Grid& g, const FragmentDistribution& f, const Jet* p, Jet* A) const {
  build_matrix(g, f, p, A, Segments::kCellMass);
}

void FixedPivotBreakage::build(const Grid& g, const FragmentDistribution& f, const double* p, double* A) const {
  build_matrix(g, f, p, A, Segments::kPivotIntervals);
}
void FixedPivotBreakage::build(const Grid& g, const FragmentDistribution& f, const Jet* p, Jet* A) const {
  build_matrix(g, f, p, A, Segments::kPivotIntervals);
}
void CellAverageBreakage::build(const Grid& g, const FragmentDistribution& f, const double* p, double* A) const {
  build_matrix(g, f, p, A, Segments::kCells);
}
void CellAverageBreakage::build(const Grid& g, const FragmentDistribution& f, const Jet* p, Jet* A) const {
  build_matrix(g, f, p, A, Segments::kCells);
}

}  // namespace granuflow::kernels
