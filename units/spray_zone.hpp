#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Spray zone of paper 001 (Eqs. (27)-(35), (40)-(51), (55)-(57)): from the bed's hold-up (read through its
// probe) and the deposited liquid, the DEM-surrogate closures give per class the liquid deposited, the wetted
// surface fraction and the wet-spot moisture that the glass-transition agglomeration kernel needs (with a binder
// solution, the binder's solids counted in the wet spot), and Eq. (29) at the cell faces, the shape of the binder's
// layering in the bed (docs/binder_granulation.md).
// Zero hold-up: every state is algebraic.
void register_spray_zone(Registry<Unit>& r);
}  // namespace granuflow::units
