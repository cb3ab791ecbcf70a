#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Batch, well-mixed population balance over particle volume (paper 001, Eq. (20)): class numbers N_i on a grid,
// with aggregation, breakage and growth each chosen by name (kernel and scheme) or left out, an initial
// distribution by settings and parameters, and book-keeping states for what leaves the grid. Supplies an
// analytic Jacobian. Reports number, mass, d10,3 / d50,3 / d90,3 and the mass-balance closure.
void register_pbm_batch(Registry<Unit>& r);
}  // namespace granuflow::units
