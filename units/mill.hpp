#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// A mill for the oversize of a sieve-mill recycle (paper 003, section 7.5.1): a comminution law
// (kernels/comminution) spreads each feed class over finer classes, conserving mass exactly.
void register_mill(Registry<Unit>& r);
}  // namespace granuflow::units
