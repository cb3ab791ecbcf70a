#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Batch fluid bed of paper 001: the population balance over size (dry-solid mass and water per class,
// Eqs. (18)-(26)) with the glass-transition agglomeration kernel (Eqs. (36)-(39), (52)-(54)) and Vogel-Peukert
// breakage (Eqs. (90)-(93)); particle drying after Burgschweiger with the normalized drying curve and BET
// isotherm (Eqs. (58), (70)-(83)); gas-solid heat transfer (Eqs. (85)-(89)); one lumped solids enthalpy
// (Eqs. (59)-(60)).
void register_fluid_bed(Registry<Unit>& r);
}  // namespace granuflow::units
