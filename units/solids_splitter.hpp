#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Splitter of a solids stream into two with a fixed fraction, every size class alike.
void register_solids_splitter(Registry<Unit>& r);
}  // namespace granuflow::units
