#include "drying/drying_closures.hpp"

#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "registry.hpp"

namespace granuflow::kernels {

namespace {
// Declares a plugin's parameters under "drying_<name>"; returns the index of the first.
template <class K>
int declare_params(UnitSpec& s, Settings& st, const K& k) {
  const int first = static_cast<int>(s.params().size());
  for (ParamSpec spec : k.params()) {
    spec.name = "drying_" + spec.name;
    if (s.param_index(spec.name) >= 0)
      throw ConfigError(st.where() + ": parameter '" + spec.name + "' is declared twice in this unit");
    s.add_param(std::move(spec));
  }
  return first;
}
}  // namespace

void DryingClosures::declare(UnitSpec& s, Settings& st, const std::string& curve_default, bool surfaces) {
  const auto& reg = registries();
  std::vector<std::string> names = reg.drying_curves.names();
  if (curve_default.empty()) names.insert(names.begin(), "none");
  curve_name_ = st.get_choice("drying_curve", curve_default.empty() ? "none" : curve_default, names,
                              "normalized drying curve of the falling-rate period (paper 000, section 5.4.1)" +
                                  std::string(curve_default.empty() ? "; none: the unit's own kinetics" : ""));
  if (curve_name_ != "none") {
    curve_ = reg.drying_curves.create(curve_name_, st.where());
    curve_first_ = declare_params(s, st, *curve_);
  }
  if (!surfaces) return;
  const std::string surf =
      st.get_choice("drying_surface", "film", reg.drying_surfaces.names(),
                    "surface the particles dry from: film, correction, coverage, droplet_height (paper 000, 5.2)");
  surface_ = reg.drying_surfaces.create(surf, st.where());
  surface_first_ = declare_params(s, st, *surface_);
}

void DryingClosures::check(const double* p, const std::string& where) const {
  const ClassState<double> none;
  if (curve_) curve_->check(none, p + curve_first_, where);
  if (surface_) surface_->check(none, p + surface_first_, where);
}

}  // namespace granuflow::kernels
