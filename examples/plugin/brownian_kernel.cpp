// Perikinetic (Brownian) aggregation of small particles in a quiescent liquid, Smoluchowski's continuum-regime
// kernel (Smoluchowski 1917; e.g. Elimelech et al. 1995, Particle Deposition and Aggregation, Eq. (6.17)):
//     beta_conc(d_i, d_j) = 2 k_B T / (3 mu) (d_i + d_j)^2 / (d_i d_j)     [m^3/s]
// granuflow's kernels are rates per pair of absolute particle numbers (kernels/aggregation/aggregation_kernel.hpp),
// so the concentration-based coefficient is divided by the suspension volume V the particles are dispersed in.
#include <kernels/aggregation/aggregation_kernel.hpp>
#include <kernels/registry.hpp>

namespace {

using granuflow::ParamSpec;
using granuflow::kernels::ClassState;

constexpr double kBoltzmann = 1.380649e-23;  // J/K, exact since the 2019 SI redefinition

class BrownianKernel : public granuflow::kernels::PairKernel<BrownianKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"T", "K", 293.15, 200.0, 700.0, "temperature of the suspension", "operating input"},
            {"mu", "Pa s", 1.0016e-3, 1e-6, 10.0, "dynamic viscosity of the liquid",
             "water at 20 degC, IAPWS 2008 (Huber et al. 2009, J. Phys. Chem. Ref. Data 38, 101)"},
            {"V", "m3", 1.0, 1e-12, 1e6, "volume of suspension the particles are dispersed in", "operating input"}};
  }
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    const double di = s.diameter[i], dj = s.diameter[j];
    return 2.0 * kBoltzmann * p[0] / (3.0 * p[1] * p[2]) * ((di + dj) * (di + dj) / (di * dj));
  }
};

}  // namespace

void register_brownian_kernel() {
  granuflow::kernels::registries().aggregation.add(
      "brownian", "Smoluchowski's perikinetic kernel 2 k_B T / (3 mu V) (d_i + d_j)^2 / (d_i d_j) (example plugin)",
      [] { return std::make_unique<BrownianKernel>(); });
}
