// Layering of the solids a spray deposits on a bed's population (a binder solution whose water dries): number-
// conserving growth on the size grid by the population engine's finite-volume schemes (kernels/discretization/
// fv_growth.hpp, paper 003, Eqs. (7.32), (7.34)), volume-normalized so that the particles gain exactly the deposited
// solids mass m_s (the layer takes the particles' envelope density), with a growth rate of shape s(d) at the cell
// faces. The fluid bed gives s = Eq. (29)'s residence-time fraction tau(d) of paper 001: a particle's volume then
// grows in proportion to tau d^2, its share of Eq. (44)'s liquid split (docs/binder_granulation.md). Particles
// growing past the top face stay in the top class with their volume (the bed's fold of paper 001); the water of a
// class moves with its particles (from the donor cell of each face).
#pragma once
#include <memory>
#include <vector>

#include "granuflow/ad.hpp"
#include "granuflow/unit.hpp"
#include "kernels/discretization/fv_growth.hpp"

namespace granuflow {
class Settings;
}

namespace granuflow::units {

class BedLayering {
 public:
  // Reads the setting layering_scheme (default fv_van_albada: smooth, for the integrator).
  void declare(Settings& st, const kernels::Grid& g);

  template <class T>
  struct Scratch {
    std::vector<T> F;
    std::vector<int> donor;
    std::vector<double> dF;  // (n + 1) x n, doubles only
  };
  // The classes: numbers N, water W, floors of the water per particle, particle masses pm (kg), and the layer's
  // density rho (kg/m^3); `shape` holds s at the n + 1 faces.
  template <class T>
  struct Classes {
    const T *N, *W, *floor, *pm, *shape;
    T rho;
  };
  // Adds the class mass and water rates (kg/s) of layering m_s kg/s of solids to dM and dW.
  template <class T>
  void rates(const Classes<T>& k, const T& m_s, Scratch<T>& sc, T* dM, T* dW) const;
  // Where the inputs sit in the unit's Jacobian: rows of the mass and water residuals (unit-local, residual
  // x' - rate), columns of M and W (global), of the shape at the faces, and of the inputs m_s depends on with
  // dm_s/d(input) (m_s = w sum_j mdot_j: the column of w with sum_j mdot_j, those of mdot_j with w).
  struct Columns {
    int m_row, w_row, m_col, w_col;
    std::vector<int> shape_cols;                      // n + 1
    std::vector<std::pair<int, double>> amount_cols;  // (column, dm_s/d input)
  };
  // d(rates)/d(M, W, shape, inputs of m_s) into the sink, exact: the rates' derivatives along m_s and the shape by
  // forward AD (they are not zero at m_s = 0: a water spray's Jacobian holds the derivative along w).
  void jacobian(const Classes<double>& k, double m_s, Scratch<double>& sc, const Columns& cols,
                JacobianSink& sink) const;

 private:
  std::unique_ptr<kernels::FvGrowth> fv_;
  int n_ = 0;
  double x_hi_ = 0.0;  // virtual pivot above the grid, m^3
};

// Whether a value is exactly zero and carries no derivative: layering of nothing is skipped, so that a water spray
// costs nothing and changes no bit of a result.
inline bool carries_nothing(double v) { return v == 0.0; }
inline bool carries_nothing(const Jet& v) { return v.a == 0.0 && (v.v.array() == 0.0).all(); }

}  // namespace granuflow::units
