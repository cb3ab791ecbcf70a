// The one list of built-in population-balance plugins, each family in its own registry: physical kernels
// (aggregation beta, breakage selection S and fragments b, growth G), numerical schemes (aggregation,
// breakage, growth), and the separation curves and comminution laws of classifiers and mills. A scene names one of
// each by string; unknown names throw ConfigError listing the valid ones.
// Adding a kernel: its file pair, one call in registry.cpp, one line in CMakeLists.txt.
#pragma once
#include "aggregation/aggregation_kernel.hpp"
#include "breakage/fragment_distribution.hpp"
#include "breakage/selection_rate.hpp"
#include "classification/separation_curve.hpp"
#include "comminution/comminution_law.hpp"
#include "discretization/aggregation_scheme.hpp"
#include "discretization/breakage_scheme.hpp"
#include "discretization/fv_growth.hpp"
#include "drying/drying_curve.hpp"
#include "drying/drying_surface.hpp"
#include "granuflow/registry.hpp"
#include "growth/growth_law.hpp"

namespace granuflow::kernels {

struct KernelRegistries {
  Registry<AggregationKernel> aggregation{"aggregation kernel"};
  Registry<SelectionRate> selection{"breakage selection rate"};
  Registry<FragmentDistribution> fragments{"fragment distribution"};
  Registry<GrowthLaw> growth{"growth law"};
  Registry<AggregationScheme> aggregation_schemes{"aggregation scheme"};
  Registry<BreakageScheme> breakage_schemes{"breakage scheme"};
  Registry<FvGrowth> growth_schemes{"growth scheme"};
  // Classifiers and mills of solids processes (sieve, classifying discharge, mill): not population-balance
  // mechanisms, but plugins of the same kind.
  Registry<SeparationCurve> separation{"separation curve"};
  Registry<ComminutionLaw> comminution{"comminution law"};
  // The drying closures of a particle hold-up (paper 000, sections 5.2, 5.4.1).
  Registry<DryingCurve> drying_curves{"drying curve"};
  Registry<DryingSurface> drying_surfaces{"drying surface"};

  // Every family under the name the reference and the plugin listing give it: one list, so that a new family shows
  // everywhere at once (the plugin listing had missed the drying families).
  template <class F>
  void for_each(F&& f) const {
    f("aggregation", aggregation);
    f("breakage_selection", selection);
    f("breakage_fragments", fragments);
    f("growth", growth);
    f("aggregation_scheme", aggregation_schemes);
    f("breakage_scheme", breakage_schemes);
    f("growth_scheme", growth_schemes);
    f("separation", separation);
    f("comminution", comminution);
    f("drying_curve", drying_curves);
    f("drying_surface", drying_surfaces);
  }
};

void register_all(KernelRegistries& r);

// The process-wide registries with every built-in plugin, created on first use. Prototype kernels (e.g. Python
// callables, aggregation/callback.hpp) are added here before a flowsheet is built.
KernelRegistries& registries();

}  // namespace granuflow::kernels
