#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Batch, well-mixed population balance over solid volume x liquid volume (paper 002, Eqs. (6)-(10)): numbers N_ij per
// bin on the particle system's solid grid times a uniform liquid grid, aggregation by a named kernel (the DEM kernel
// dem_collision of Eqs. (11)-(13) in the paper's case), liquid added as whole droplets or as a continuous flow
// while the spray is on, and drying where the scene asks for it. Reports Eqs. (14)-(16) (mass frequency per size class,
// average diameter, average liquid fraction), the solid and liquid balances and the grid coordinates for 2-D plots.
// docs/pbm_2d.md describes the model and its verification.
void register_pbm_2d(Registry<Unit>& r);
}  // namespace granuflow::units
