#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Liquid source: mass flow, temperature and dissolved-solids fraction, each a parameter or piecewise input.
void register_liquid_feed(Registry<Unit>& r);
}  // namespace granuflow::units
