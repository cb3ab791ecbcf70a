// ParticleChamber's workspace (particle_chamber.hpp), shared by its source files.
#pragma once
#include <vector>

#include "granuflow/unit.hpp"
#include "kernels/population/population.hpp"
#include "particle_chamber.hpp"

namespace granuflow::units {

struct ParticleChamber::Work : Workspace {
  kernels::Population::WorkPtr pop;
  // particle mass, surface per mass and the number floor kMassFloor / m of each class at the run's parameters
  std::vector<double> pm, spm, floor;
  Classifier::Cache cls;
  template <class T>
  struct Scratch {
    std::vector<T> pm, spm, N, floor, dM, dW, dN, F, ones, temp, in_m, in_w, gather;
    std::vector<T> om[kOutlets], ow[kOutlets];  // per outlet the flows of each class, solids and water (outflows())
    // composition: per component c >= 1 (block c - 1 of n) its rates, the engine's rates, inflows and outflows; the
    // volume balance of the layering per class
    std::vector<T> dQ, eq, in_q, dv, oq[kOutlets];
    std::vector<int> donor;
    void resize_components(int n, int extra) {
      for (auto* v : {&dQ, &eq, &in_q}) v->assign(size_t(n) * extra, T(0.0));
      for (int k = 0; k < kOutlets; ++k) oq[k].assign(size_t(n) * extra, T(0.0));
      dv.assign(n, T(0.0));
    }
    void resize(int n) {
      for (auto* v : {&pm, &spm, &N, &floor, &dM, &dW, &dN, &temp, &in_m, &in_w}) v->assign(n, T(0.0));
      for (int k = 0; k < kOutlets; ++k) om[k].assign(n, T(0.0)), ow[k].assign(n, T(0.0));  // dry: ow stays 0
      F.assign(n + 1, T(0.0)), ones.assign(n + 1, T(1.0)), donor.assign(n + 1, -1);
    }
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  std::vector<double> dF;        // growth flux Jacobian, (n + 1) x n
  kernels::Population::Map map;  // the engine's inputs and rates in the unit's Jacobian (built on first use)
  bool mapped = false;
};

}  // namespace granuflow::units
