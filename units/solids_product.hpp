#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// A solids sink: integrates the dry solids, water and enthalpy it receives (quadratures) and reports the size
// distribution of the stream arriving.
void register_solids_product(Registry<Unit>& r);
}  // namespace granuflow::units
