#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// A two-deck screen (paper 003, section 7.5.1): oversize on the upper deck, product between the decks, undersize
// through both; one separation curve per deck (kernels/classification).
void register_sieve(Registry<Unit>& r);
}  // namespace granuflow::units
