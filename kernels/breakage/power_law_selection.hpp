// Power-law selection rate S(v) = S0 (v / v_ref)^a; a = 1 is the linear rate of Ziff & McGrady's analytic
// solution (docs/verification.md: S(v) = v with S0 = v_ref = 1).
#pragma once
#include <cmath>

#include "breakage/selection_rate.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class PowerLawSelection : public PerClassRate<PowerLawSelection> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"s0", "1/s", 1.0, 0.0, 1e6, "selection rate at v = v_ref", "Austin 1971 (power-law selection)"},
            reference_volume_param(),
            {"a", "-", 1.0, -5.0, 5.0, "exponent on the particle volume", "Austin 1971 (power-law selection)"}};
  }
  template <class T>
  T rate(const ClassState<T>& s, int i, const T* p) const {
    using std::pow;
    return p[0] * pow(s.volume[i] / p[1], p[2]);
  }
};

// S(v) = s0 v / v_ref (Ziff & McGrady's analytic case).
class LinearSelection : public PerClassRate<LinearSelection> {
 public:
  std::vector<ParamSpec> params() const override {
    return {{"s0", "1/s", 1.0, 0.0, 1e6, "selection rate at v = v_ref", "Ziff & McGrady 1985"},
            reference_volume_param()};
  }
  template <class T>
  T rate(const ClassState<T>& s, int i, const T* p) const {
    return p[0] * (s.volume[i] / p[1]);
  }
};

// Registers "power_law" and "linear".
void register_power_law_selection(Registry<SelectionRate>& r);

}  // namespace granuflow::kernels
