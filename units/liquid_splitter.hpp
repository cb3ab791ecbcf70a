#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Splits a liquid stream into out1 (fraction `split`) and out2 at the inlet state.
void register_liquid_splitter(Registry<Unit>& r);
}  // namespace granuflow::units
