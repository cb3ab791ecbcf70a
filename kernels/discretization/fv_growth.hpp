// Growth (layering) on the size grid: a conservative finite-volume scheme in the diameter coordinate for
//     dn/dt + d(G n)/dd = 0        (paper 003, Eqs. (7.32), (7.34))
// with the class numbers N_i as cell integrals of n over [d_i, d_{i+1}] (diameters of the volume edges):
//     dN_i/dt = F_{i} - F_{i+1},   F_f = G(d_f) n_f   (number flux through face f).
// The face density n_f comes from the upwind cell with a limited slope (Koren 1993: the kappa = 1/3 reconstruction,
// third-order upwind-biased
// where smooth, first order at extrema and steep fronts), which keeps N >= 0 and adds little numerical
// diffusion; fv_upwind is the first-order scheme. fv_van_albada takes van Albada's smooth slope ab(a + b)/(a^2 + b^2)
// (van Albada, van Leer & Roberts 1982) instead: second order where smooth and differentiable everywhere but at
// a = b = 0, so that implicit integrators and Newton do not meet the switches of a piecewise limiter (about half the
// steps and a third of the Jacobians of fv_koren on a sieve-mill loop); it is not TVD at extrema. Particles crossing
// the top face leave the grid at the virtual pivot (counted as number/volume above), those crossing the bottom face
// downwards at x_lo.
//
// Volume created by growth: W = sum_f F_f (x_f - x_{f-1}) (pivot above minus pivot below the face) is exactly
// sum_i x_i dN_i/dt plus what leaves, so bookkeeping closes to round-off. For volume-normalized laws
// (growth_law.hpp) the growth rate of term k is a_k s_k(d_f) / I_k with I_k = sum_f s_k(d_f) n_f (x_f - x_{f-1}),
// so W = sum_k a_k exactly: paper 003's Eq. (7.33) delivers the sprayed solids volume to the particles to
// round-off, with the moment mu_2 of Eq. (7.33) evaluated by the scheme's own quadrature.
#pragma once
#include <vector>

#include "discretization/grid.hpp"
#include "discretization/redistribution.hpp"
#include "granuflow/ad.hpp"

namespace granuflow::kernels {

enum class Limiter { kNone, kKoren, kVanAlbada };

// Growth-law values at the n + 1 faces (see growth/growth_law.hpp).
template <class T>
struct GrowthTerms {
  int terms = 0;
  const T* shape = nullptr;   // terms x (n + 1)
  const T* amount = nullptr;  // terms
  bool normalized = false;
};

class FvGrowth {
 public:
  explicit FvGrowth(Limiter limiter) : limiter_(limiter) {}
  void setup(const Grid& g);
  int faces() const { return n_ + 1; }
  const std::vector<double>& face_diameters() const { return d_face_; }

  // Number fluxes F_f through the n + 1 faces (positive upward) and the donor cell of each face (-1: nothing
  // crosses the boundary inward); returns the volume creation rate W = sum_f F_f (x_f - x_{f-1}) (m^3/s).
  double fluxes(const double* N, const GrowthTerms<double>& g, double* F, int* donor) const;
  Jet fluxes(const Jet* N, const GrowthTerms<Jet>& g, Jet* F, int* donor) const;
  // dF_f/dN_l, (n + 1) x n row-major.
  void flux_jacobian(const double* N, const GrowthTerms<double>& g, double* dF) const;
  const std::vector<double>& face_volume_steps() const { return dx_face_; }  // x_f - x_{f-1}, virtual pivots at ends

 private:
  // A face's cells: the donor (-1: nothing crosses the boundary inward), its neighbours downwind (towards the face)
  // and upwind, the slope normalizations towards them, and whether both neighbours exist and a limiter is used.
  struct Stencil {
    int donor = -1, down = -1, up = -1;
    double cd = 0.0, cu = 0.0;
    bool full = false;
  };
  Stencil stencil(int f, bool upward) const;
  // d phi_f / d N_col for the (up to) three cells of a face (flux_jacobian).
  struct FaceDerivatives {
    int cols[3];
    double d[3];
  };
  FaceDerivatives derivatives(const Stencil& s, double da, double db) const;
  // What flux_jacobian reads besides the fluxes: face densities, their derivatives, 1 / I_k per term.
  struct JacobianParts {
    std::vector<double> phi, inv;
    std::vector<FaceDerivatives> dphi;
  };
  template <class T, Limiter L, bool kUpward, bool kDerivatives>
  void face_densities(const T* rho, const T* G, T* phi, int* donor, FaceDerivatives* dphi) const;
  // The fluxes of every path (doubles, Jets, each limiter; the Jacobian's with `jac`).
  template <class T, Limiter L>
  T flux_values(const T* N, const GrowthTerms<T>& g, T* F, int* donor, std::vector<T>& G, JacobianParts* jac) const;
  // Per term k of a growth law: its scale a_k / I_k (normalized laws, I_k = sum_f s_k(d_f) phi_f dx_f from the face
  // densities phi, 1 / I_k kept for the Jacobian) or a_k; a normalized term with I_k <= 0 has nothing to grow on.
  template <class T>
  struct TermScale {
    T value, inv;
    bool grows;
  };
  template <class T>
  void term_scales(const GrowthTerms<T>& g, const T* phi, TermScale<T>* ts) const;
  template <class T>
  void growth_rates(const GrowthTerms<T>& g, const TermScale<T>* ts, T* G) const;

  Limiter limiter_;
  const Grid* grid_ = nullptr;
  int n_ = 0;
  std::vector<double> width_;           // cell widths in d, m
  std::vector<double> cplus_, cminus_;  // slope normalizations width_i / (centre distance) to the right / left
  std::vector<double> d_face_;          // m, n + 1
  std::vector<double> dx_face_;         // m^3: pivot above minus pivot below each face (virtual pivots at the ends)
};

}  // namespace granuflow::kernels
