// DEM-informed kernel of paper 002, Eqs. (11)-(13): beta_ij = C_ij psi_ij with the collision frequency per pair
// C_ij = N_coll,ij / (F_i F_j dt) counted in a DEM run (Eq. (12); collision_frequency_table() turns the counts
// into a data table) and the liquid-content efficiency psi_ij = psi0 when the liquid content (liquid volume
// over particle volume) reaches LC_min, else 0 (Eq. (13)). Eq. (13) prints "either partner" for psi0 and
// "either partner below" for 0; the setting <prefix>wet_rule chooses: either (default, the first line) or both.
#pragma once
#include <string>

#include "aggregation/aggregation_kernel.hpp"
#include "data_tables.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

enum class WetRule { kEither, kBoth };

class DemCollisionKernel : public PairKernel<DemCollisionKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"psi0", "-", 0.01, 0.0, 1.0, "collision efficiency of wet pairs", "paper 002, Eq. (13)"},
            {"lc_min", "-", 0.2, 0.0, 1.0, "minimum liquid content for coalescence", "paper 002, Eq. (13)"}};
  }
  ClassNeeds needs() const override {
    ClassNeeds n;
    n.liquid_fraction = true;
    return n;
  }
  void declare(Settings& s, const std::string& prefix) override;
  void check(const ClassState<double>& s, const double* p, const std::string& where) const override;
  template <class T>
  T factor(const ClassState<T>&, int i, int j, const T* p) const {
    return frequency_->at(i, j) * p[0];  // Eq. (11), paper 002: C_ij psi0
  }
  static constexpr int kFeatures = 1;  // the liquid content
  template <class T>
  void features(const ClassState<T>& s, int i, const T*, T* phi) const {
    phi[0] = s.liquid_fraction()[i];
  }
  template <class T>
  T efficiency(const T* a, const T* b, const T* p) const {
    const bool wi = !(a[0] < p[1]), wj = !(b[0] < p[1]);
    return (rule_ == WetRule::kEither ? (wi || wj) : (wi && wj)) ? T(1.0) : T(0.0);  // Eq. (13), paper 002
  }

 private:
  const Table* frequency_ = nullptr;
  WetRule rule_ = WetRule::kEither;
};

// Eq. (12), paper 002: C_ij = N_coll,ij / (F_i F_j dt), 1/s per pair, from a symmetric n x n count matrix, the
// class numbers F during the DEM window and its length dt (s). Pairs of an empty class get 0.
Table collision_frequency_table(const std::vector<double>& counts, const std::vector<double>& numbers, double dt,
                                const std::string& source);

void register_dem_collision(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
