#include "registry.hpp"

#include "aggregation/constant.hpp"
#include "aggregation/dem_collision.hpp"
#include "aggregation/eke.hpp"
#include "aggregation/glass_transition.hpp"
#include "aggregation/kapur.hpp"
#include "aggregation/product.hpp"
#include "aggregation/shear.hpp"
#include "aggregation/stokes.hpp"
#include "aggregation/sum.hpp"
#include "breakage/fragments.hpp"
#include "breakage/power_law_selection.hpp"
#include "breakage/vogel_peukert.hpp"
#include "classification/separation_curves.hpp"
#include "comminution/comminution_laws.hpp"
#include "discretization/cell_average.hpp"
#include "discretization/fixed_pivot.hpp"
#include "drying/drying_curves.hpp"
#include "drying/drying_surfaces.hpp"
#include "growth/growth_laws.hpp"

namespace granuflow::kernels {

namespace {
void register_schemes(KernelRegistries& r) {
  r.aggregation_schemes.add("fixed_pivot", "fixed pivot technique (Kumar & Ramkrishna 1996)",
                            [] { return std::make_unique<FixedPivotAggregation>(); });
  r.aggregation_schemes.add("cell_average", "cell average technique (Kumar et al. 2006)",
                            [] { return std::make_unique<CellAverageAggregation>(); });
  r.breakage_schemes.add("fixed_pivot", "fragments split between neighbouring pivots (Kumar & Ramkrishna 1996)",
                         [] { return std::make_unique<FixedPivotBreakage>(); });
  r.breakage_schemes.add("cell_average", "fragments per cell split on the side of their mean (Kumar et al. 2008)",
                         [] { return std::make_unique<CellAverageBreakage>(); });
  r.breakage_schemes.add("cell_mass", "fragment mass per cell on the cell's pivot (number not kept; paper 001 reading)",
                         [] { return std::make_unique<CellMassBreakage>(); });
  r.growth_schemes.add("fv_koren",
                       "finite volumes in diameter, Koren limiter (kappa = 1/3: third order where smooth, positive)",
                       [] { return std::make_unique<FvGrowth>(Limiter::kKoren); });
  r.growth_schemes.add("fv_upwind", "finite volumes in diameter, first-order upwind",
                       [] { return std::make_unique<FvGrowth>(Limiter::kNone); });
  r.growth_schemes.add("fv_van_albada", "finite volumes in diameter, van Albada's smooth slope (differentiable)",
                       [] { return std::make_unique<FvGrowth>(Limiter::kVanAlbada); });
}
}  // namespace

void register_all(KernelRegistries& r) {
  register_constant(r.aggregation);
  register_sum(r.aggregation);
  register_product(r.aggregation);
  register_kapur(r.aggregation);
  register_eke(r.aggregation);
  register_shear(r.aggregation);
  register_dem_collision(r.aggregation);
  register_stokes(r.aggregation);
  register_glass_transition(r.aggregation);
  register_power_law_selection(r.selection);
  register_vogel_peukert(r.selection);
  register_fragments(r.fragments);
  register_growth_laws(r.growth);
  register_separation_curves(r.separation);
  register_comminution_laws(r.comminution);
  register_drying_curves(r.drying_curves);
  register_drying_surfaces(r.drying_surfaces);
  register_schemes(r);
}

KernelRegistries& registries() {
  static KernelRegistries r = [] {
    KernelRegistries k;
    register_all(k);
    return k;
  }();
  return r;
}

}  // namespace granuflow::kernels
