// DEM-informed kernel of paper 002, Eqs. (11)-(13): beta_ij = C_ij psi_ij with the collision frequency per pair
// C_ij = N_coll,ij / (F_i F_j dt) counted in a DEM run (Eq. (12)) and the liquid-content efficiency psi_ij = psi0
// when the liquid content (liquid volume over particle volume) reaches LC_min, else 0 (Eq. (13)).
//
// Where C comes from (settings, with the unit's prefix, e.g. agg_):
//   * collisions_file: a CSV of collision counts from the user's DEM run (docs/dem_collisions.md): class edges in
//     diameter, particles per class F, the counting window dt and the symmetric count matrix. A grid class takes
//     the collision frequency of the DEM class holding its pivot diameter; every pivot must lie inside the file's
//     edges (a ConfigError names the file and the class otherwise).
//   * collisions: the name of a data table of C_ij already loaded (data_tables.hpp), one row and column per class.
// The file says how it counts a collision of two like particles (key like_collisions): twice, as each particle
// tallies its own contacts (an unlike collision once in N_ij and once in N_ji), so that Eq. (12) as printed gives the
// rate per pair for like and unlike classes alike; or once, and its diagonal is doubled (docs/dem_collisions.md).
//
// Efficiency (setting efficiency): step, Eq. (13) as printed, or smooth, psi0 w(LC) with the logistic
// w = (1 + tanh((LC - LC_min) / lc_width)) / 2, whose derivative is continuous (docs/pbm_2d.md measures what the
// step costs the solver and how much the smooth form changes the answer). Eq. (13) prints "either partner" for
// psi0 and "either partner below" for 0; the setting wet_rule chooses: either (default, the first line) or both.
#pragma once
#include <memory>
#include <string>

#include "aggregation/aggregation_kernel.hpp"
#include "data_tables.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

enum class WetRule { kEither, kBoth };
enum class EfficiencyShape { kStep, kSmooth };

class DemCollisionKernel : public PairKernel<DemCollisionKernel> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"psi0", "-", 0.01, 0.0, 1.0, "collision efficiency of wet pairs", "paper 002, Eq. (13)"},
            {"lc_min", "-", 0.2, 0.0, 1.0, "minimum liquid content for coalescence", "paper 002, Eq. (13)"},
            {"lc_width", "-", 0.02, 1e-6, 1.0, "width of the smooth efficiency step (efficiency: smooth only)",
             "regularization of Eq. (13), paper 002; docs/pbm_2d.md"}};
  }
  ClassNeeds needs() const override {
    ClassNeeds n;
    n.liquid_fraction = true;
    return n;
  }
  void declare(Settings& s, const std::string& prefix) override;
  void check(const ClassState<double>& s, const double* p, const std::string& where) const override;
  template <class T>
  T factor(const ClassState<T>& s, int i, int j, const T* p) const {
    if (counts_) return frequency_->at(counts_->class_of(s.diameter[i]), counts_->class_of(s.diameter[j])) * p[0];
    return frequency_->at(i, j) * p[0];  // Eq. (11), paper 002: C_ij psi0
  }
  static constexpr int kFeatures = 1;  // the liquid content
  template <class T>
  void features(const ClassState<T>& s, int i, const T*, T* phi) const {
    phi[0] = s.liquid_fraction()[i];
  }
  template <class T>
  T efficiency(const T* a, const T* b, const T* p) const {
    const T wi = wet(a[0], p), wj = wet(b[0], p);
    return rule_ == WetRule::kEither ? T(wi + wj - wi * wj) : T(wi * wj);  // Eq. (13), paper 002
  }
  // either: 1 - (1 - w_i)(1 - w_j); both: w_i w_j.
  int efficiency_terms(const double* phi, int n, const double* p, double* h, double* sign) const override;
  // The wet weight of one partner: 1 or 0 (step), or the logistic (smooth). The step takes contents within
  // kContentRoundOff below LC_min as reaching it: grid pivots can sit exactly on the threshold (a 2-D bin of four
  // primaries and one droplet of their size has LC = 0.2), and the last bit of the pivots' arithmetic must not
  // decide whether they stick.
  static constexpr double kContentRoundOff = 1e-9;
  template <class T>
  T wet(const T& lc, const T* p) const {
    if (shape_ == EfficiencyShape::kStep) return lc < p[1] - kContentRoundOff ? T(0.0) : T(1.0);
    using std::tanh;
    return T(0.5) * (T(1.0) + tanh((lc - p[1]) / p[2]));
  }
  const CollisionCounts* counts() const { return counts_.get(); }

 private:
  const Table* frequency_ = nullptr;
  std::shared_ptr<const CollisionCounts> counts_;  // when C comes from a collision file
  std::shared_ptr<const Table> owned_;             // C of the collision file
  WetRule rule_ = WetRule::kEither;
  EfficiencyShape shape_ = EfficiencyShape::kStep;
};

// Eq. (12), paper 002: C_ij = N_coll,ij / (F_i F_j dt), 1/s per pair, from a symmetric n x n count matrix, the
// class numbers F during the DEM window and its length dt (s). Pairs of an empty class get 0.
Table collision_frequency_table(const std::vector<double>& counts, const std::vector<double>& numbers, double dt,
                                const std::string& source);
Table collision_frequency_table(const CollisionCounts& c);

void register_dem_collision(Registry<AggregationKernel>& r);

}  // namespace granuflow::kernels
