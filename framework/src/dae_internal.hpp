// What the pieces of the DAE system (dae_*.cpp) share beyond dae_system.hpp: the AD plan of a unit and the
// context a unit's functions receive. Internal to the framework library.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/dae_system.hpp"

namespace granuflow {

// How the AD sweeps of one unit seed their directions. A direction is a class block (one column per class, all
// classes at once: class rows may only read their own class, so the columns never mix), a single shared column, or
// a reduction (the sum's derivative is cut and the reduction seeded as an independent variable; its own derivative
// is collected term by term and re-enters as an outer product).
struct DaeSystem::AdPlan {
  enum Kind { kClass, kCol, kReduction };
  struct Dir {
    Kind kind;
    int index;  // class block, position in local_cols_, or reduction
  };
  std::vector<Dir> dirs;
  std::vector<std::vector<int>> class_cols;  // [block][class] global column, -1 (open optional port)
  std::vector<std::vector<int>> class_pos;   // [block][class] position in local_cols_
  std::vector<char> class_seeded;            // explicit units' own blocks are rows only (identity columns)
  std::vector<int> row_class;                // per own state: its class, or -1 (scalar row)
  int reductions = 0;
  bool recorded = false;  // the unit needs a recorder (reductions, or an analytic part to skip)
};

template <class T>
Ctx<T> DaeSystem::ctx(int u, double t, const T* y, const T* yp, const std::vector<std::vector<T>>& params, T* r) const {
  const UnitInstance& inst = fs_.units()[u];
  Ctx<T> c{t, y, yp, params[u].data(), r, inst.offset, &inst.port_index, segment_start_};
  c.work = ws_[u].get();
  c.port_runs = &inst.port_runs;
  if (inst.shared >= 0) c.shared = params[inst.shared].data();
  return c;
}

// Defined in dae_residual.cpp, where both instantiations the pieces use are made.
extern template void DaeSystem::evaluate_explicit<double>(double, double*, double*,
                                                          const std::vector<std::vector<double>>&, std::vector<double>&,
                                                          const std::vector<int>*);
extern template void DaeSystem::evaluate_explicit<Jet>(double, Jet*, Jet*, const std::vector<std::vector<Jet>>&,
                                                       std::vector<Jet>&, const std::vector<int>*);

extern template void DaeSystem::drive_states<double>(const double*, std::vector<std::vector<double>>&, int) const;
extern template void DaeSystem::drive_states<Jet>(const Jet*, std::vector<std::vector<Jet>>&, int) const;
extern template void DaeSystem::drive_outputs<double>(double, const double*, const double*,
                                                      std::vector<std::vector<double>>&, int);
extern template void DaeSystem::drive_outputs<Jet>(double, const Jet*, const Jet*, std::vector<std::vector<Jet>>&, int);

}  // namespace granuflow
