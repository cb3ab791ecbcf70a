// Stokes-criterion kernel (paper 003, Eqs. (7.57)-(7.58); Ennis et al. 1991): a collision sticks when the
// viscous Stokes number is below the critical one,
//     St_ij = 2 M u_coll / (3 pi mu_l d^2) < St* = (1 + 1/e) ln(h / h_a),
// with M and d the harmonic means of the partners' masses and diameters ("averages considering both colliding
// particles", paper 003). beta_ij = beta0 for sticking pairs, else 0. A step in the sizes: state-independent,
// evaluated once per run; its parameters have no useful derivatives.
#pragma once
#include <cmath>

#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"
#include "particle_geometry.hpp"

namespace granuflow::kernels {

class StokesKernel : public PairKernel<StokesKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"beta0", "1/s", 1.0, 0.0, 1e6, "rate coefficient of sticking pairs",
             "user choice (paper 003, Eqs. (7.57)-(7.58) give only the criterion)"},
            {"u_coll", "m/s", 0.5, 0.0, 100.0, "collision velocity", "paper 003, Eq. (7.57)"},
            {"mu_l", "Pa s", 1e-3, 1e-6, 1e6, "binder viscosity", "paper 003, Eq. (7.57)"},
            {"h", "m", 10e-6, 1e-9, 1e-2, "thickness of the liquid layer", "paper 003, Eq. (7.58)"},
            {"h_a", "m", 1e-6, 1e-9, 1e-2, "height of the surface asperities", "paper 003, Eq. (7.58)"},
            {"e", "-", 0.5, 1e-3, 1.0, "coefficient of restitution", "paper 003, Eq. (7.58)"},
            {"rho", "kg/m3", 1000.0, 1.0, 1e5, "particle density for the masses", "paper 003, Eq. (7.57)"}};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    using std::log;
    const T mi = p[6] * s.volume[i], mj = p[6] * s.volume[j];
    const T m = 2.0 * mi * mj / (mi + mj);
    const double d = 2.0 * s.diameter[i] * s.diameter[j] / (s.diameter[i] + s.diameter[j]);
    const T st = 2.0 * m * p[1] / (3.0 * kPi * p[2] * d * d);  // Eq. (7.57), paper 003
    const T st_crit = (1.0 + 1.0 / p[5]) * log(p[3] / p[4]);   // Eq. (7.58), paper 003
    return st < st_crit ? p[0] : T(0.0);
  }
};

void register_stokes(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
