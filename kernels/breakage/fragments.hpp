// Fragment distributions (fragment_distribution.hpp gives the contract B(v|u)):
//  * uniform_binary: two fragments, uniform in volume, b(v|u) = 2/u: B = (v/u)^2 (Ziff & McGrady 1985);
//  * power_law: B = (v/u)^p, p > 1, i.e. b(v|u) = p u v^(p-2) / u^p and p/(p-1) fragments per event
//    (p = 2 is uniform_binary; smaller p makes more fines);
//  * tanh_power_law: paper 001, Eq. (93): a power law in the diameter ratio with a tanh cut-off on the fragment
//    size, renormalized at the parent (kernels/breakage/paper001_breakage_laws.hpp). Read as the cumulative
//    volume (mass) fraction; with q < 3 the number of fragments diverges at zero size, which only the part
//    below the grid sees (tracked as volume below, or folded into the first class).
#pragma once
#include <cmath>

#include "breakage/fragment_distribution.hpp"
#include "breakage/paper001_breakage_laws.hpp"
#include "discretization/grid.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class UniformBinaryFragments : public FragmentLaw<UniformBinaryFragments> {
 public:
  template <class T>
  T cumulative_t(double v, double u, const T*) const {
    return T((v / u) * (v / u));
  }
  template <class T>
  T number_t(double a, double b, double u, const T*) const {
    return T(2.0 * (b - a) / u);
  }
};

class PowerLawFragments : public FragmentLaw<PowerLawFragments> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"p", "-", 2.0, 1.01, 20.0, "exponent of the cumulative volume fraction (v/u)^p", "Austin 1971"}};
  }
  template <class T>
  T cumulative_t(double v, double u, const T* p) const {
    using std::pow;
    return pow(T(v / u), p[0]);
  }
  template <class T>
  T number_t(double a, double b, double u, const T* p) const {
    using std::pow;
    return p[0] / (p[0] - 1.0) * (pow(T(b / u), p[0] - 1.0) - pow(T(a / u), p[0] - 1.0));
  }
};

class TanhPowerLawFragments : public FragmentLaw<TanhPowerLawFragments> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"q_frag", "-", paper001::defaults::kFragmentExponent, 0.01, 10.0,
             "power-law exponent on d/d_parent, Eq. (93)", "paper 001, Table 10"},
            {"d_frag_min", "m", paper001::defaults::kFragmentDiameterMin, 1e-7, 1e-2, "minimum fragment size, Eq. (93)",
             "paper 001, Table 10"}};
  }
  template <class T>
  T cumulative_t(double v, double u, const T* p) const {  // Eq. (93), paper 001
    return paper001::cumulative_fragment_distribution(T(diameter_of_volume(v)), T(diameter_of_volume(u)), p[0], p[1]);
  }
  template <class T>
  T number_t(double a, double b, double u, const T* p) const {
    return this->number_by_parts(a, b, u, p);
  }
};

void register_fragments(Registry<FragmentDistribution>& r);

}  // namespace granuflow::kernels
