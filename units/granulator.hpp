#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// The chamber of a continuous (or batch) spray fluidized-bed granulator, well mixed (paper 003, sections 7.5.1 and
// 7.5.3): layering growth from the spray, a solids feed, and a product discharge, unclassified or classified by a
// separation curve, with the bed mass free or held by a discharge controller (units/particle_chamber.hpp).
void register_granulator(Registry<Unit>& r);
}  // namespace granuflow::units
