#pragma once
#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
namespace granuflow::units {
// Droplet evaporation before deposition (paper 001, Eqs. (66)-(69)): splits the spray into the part that
// evaporates in the chamber gas ("vapour", still liquid at the spray temperature: the gas supplies the
// sensible and latent heat) and the part deposited on the particles ("deposit"). Only water evaporates: the solids
// dissolved in the spray (its w) all stay in the deposit, concentrated (docs/binder_granulation.md).
void register_droplet_evaporation(Registry<Unit>& r);
}  // namespace granuflow::units
