// The outlet of a particle chamber (particle_chamber.hpp) as its zero-hold-up companion unit (UnitSpec::add_companion):
// from the chamber's hold-up M_i, W_i and its outlet rate r (per second), the flows
//     mdot_i = r f_i M_i,   water_i = r f_i W_i,
// f_i the cell fractions of the chamber's classifying discharge (1 for a well-mixed outlet). These flows are explicit
// in the chamber's states, so as an explicit unit they are evaluated inline and never enter the Newton system: the
// chamber's own unknowns are its hold-up and one rate per outlet, not its hold-up and every outlet flow.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/stream.hpp"
#include "granuflow/unit.hpp"
#include "particles.hpp"

namespace granuflow::units {

class Classifier;

// A chamber's state as its outlets read it: per class dry-solid and water mass (kg), temperature (K) and the rate
// of one outlet (1/s).
StreamKind chamber_holdup();
// With `components` > 1 (particles.hpp), then per component c >= 1 its class masses (kg).
StreamKind chamber_holdup(int components);
namespace holdup_fields {
using holdup_layout::mass, holdup_layout::water, holdup_layout::T;
inline int rate(int classes) { return holdup_layout::last(classes); }
inline int component(int classes, int c, int i) { return 2 * classes + 2 + (c - 1) * classes + i; }
}  // namespace holdup_fields

struct ChamberOutletSpec {
  int classes = 0;
  bool wet = false;                        // per-class water flows (else the chamber's zero water passes through)
  const Classifier* classifier = nullptr;  // the owner's separation curve, read with the owner's parameters
  std::vector<double> diameters;           // pivot diameters of the size grid (m)
  int components = 1;                      // named solids: the flows of each after the first, r f_i Q_c,i
};

std::unique_ptr<Unit> make_chamber_outlet(const std::string& owner, ChamberOutletSpec spec);

// The flows out[i] = r f_i h_i of one field (dry solids or water) through an outlet (f_i = 1 without a classifier):
// plain array loops, written once for the outlet and for the chamber's own balances.
template <class T>
void outlet_flows(int n, const T& r, const T* frac, const T* h, T* out) {
  if (frac) {
    for (int i = 0; i < n; ++i) out[i] = r * frac[i] * h[i];
  } else {
    for (int i = 0; i < n; ++i) out[i] = r * h[i];
  }
}

}  // namespace granuflow::units
