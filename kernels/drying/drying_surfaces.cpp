#include "drying/drying_surfaces.hpp"

#include <memory>

#include "paper001_defaults.hpp"

namespace granuflow::kernels {

namespace {
namespace def = paper001::defaults;

ParamSpec droplet_diameter() {
  return {"d_drop", "m", def::kDropletDiameter, 1e-7, 1e-2, "diameter of the deposited droplets", "paper 001, Table 9"};
}
ParamSpec liquid_density() {
  return {"rho_l",
          "kg/m3",
          def::kDropletDensity,
          100.0,
          1e4,
          "density of the liquid on the particles",
          "paper 001, Table 6"};
}
}  // namespace

std::vector<ParamSpec> CorrectedSurface::params() const {
  return {{"f_surface", "-", 1.0, 1e-4, 10.0, "correction factor of the outer surface for drying (1 = the film)",
           "paper 000, section 5.2.2 (fitted to temperature and moisture data)"}};
}

std::vector<ParamSpec> CoverageSurface::params() const { return {droplet_diameter(), liquid_density()}; }

std::vector<ParamSpec> DropletHeightSurface::params() const {
  return {droplet_diameter(),
          liquid_density(),
          {"theta", "-", kPi / 2.0, 1e-3, kPi - 1e-3,
           "contact angle of the sessile droplets, rad (pi / 2: hemispheres, h = a)",
           "paper 003, Eqs. (7.53)-(7.54); no published angle for the product: pi / 2 is the neutral cap, set the "
           "measured one"}};
}

void register_drying_surfaces(Registry<DryingSurface>& r) {
  r.add("film", "continuous liquid film over the whole outer surface (paper 000, section 5.2.1)",
        [] { return std::make_unique<FilmSurface>(); });
  r.add("correction", "outer surface times a fitted correction factor (paper 000, section 5.2.2)",
        [] { return std::make_unique<CorrectedSurface>(); });
  r.add("coverage", "surface covered by the held liquid as droplets, 1 - exp(-coating number) (paper 000, 5.2.3)",
        [] { return std::make_unique<CoverageSurface>(); });
  r.add("droplet_height", "held liquid as sessile caps at a contact angle, their interface dries (paper 000, 5.2.4)",
        [] { return std::make_unique<DropletHeightSurface>(); });
}

}  // namespace granuflow::kernels
