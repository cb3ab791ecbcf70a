// What every physical kernel of the population balance shares: its declared parameters (ParamSpec, SI unit and
// bounds) and the per-class state it reads. A kernel is a small functor written once as a template on the
// scalar type (double for residuals, Jet for Jacobians and parameter sensitivities) and wrapped for the
// registry by the family interfaces (aggregation/aggregation_kernel.hpp, breakage/selection_rate.hpp,
// breakage/fragment_distribution.hpp, growth/growth_law.hpp).
//
// Contract: params() is the kernel's static table; the owning unit declares them (with a prefix such as
// "agg_") and hands their values back as `p`, in the same order. A kernel whose needs() are all false is
// state-independent: the unit evaluates it once per run (Unit::configure) and again only when one of its
// parameter values changes (a time-dependent input), never once per residual.
#pragma once
#include <string>
#include <vector>

#include "granuflow/ad.hpp"
#include "granuflow/param.hpp"

namespace granuflow {
class Settings;
}

namespace granuflow::kernels {

// The per-class fields a kernel may read besides the sizes; the owning unit supplies them (from its states, its
// ports or, in a batch unit, as parameters).
enum class Field { kMoisture, kSpotMoisture, kTemperature, kLiquidFraction, kWettedFraction };
inline constexpr int kFields = 5;
const char* field_name(Field f);  // "moisture", ...

// Which per-class state a kernel reads besides the sizes.
struct ClassNeeds {
  bool number = false;           // particle numbers N_i (makes the kernel depend on the solution itself)
  bool moisture = false;         // liquid loading X_i, kg/kg dry solid
  bool spot_moisture = false;    // moisture of the wet spot, kg/kg dry solid (paper 001, Eq. (55))
  bool temperature = false;      // K
  bool liquid_fraction = false;  // liquid volume / particle volume, - (paper 002, Eq. (13))
  bool wetted_fraction = false;  // wetted fraction of the particle surface, - (paper 001, Eq. (41))
  bool field(Field f) const {
    const bool v[kFields] = {moisture, spot_moisture, temperature, liquid_fraction, wetted_fraction};
    return v[static_cast<int>(f)];
  }
  bool any_field() const { return moisture || spot_moisture || temperature || liquid_fraction || wetted_fraction; }
  bool any() const { return number || any_field(); }
  ClassNeeds& operator|=(const ClassNeeds& o) {
    number |= o.number, moisture |= o.moisture, spot_moisture |= o.spot_moisture, temperature |= o.temperature;
    liquid_fraction |= o.liquid_fraction, wetted_fraction |= o.wetted_fraction;
    return *this;
  }
};

// Per-class state handed to kernels. Sizes are the grid's pivots (constants); the other arrays are null unless
// the kernel declared it needs them.
template <class T>
struct ClassState {
  int n = 0;
  const double* volume = nullptr;    // m^3, pivot volumes
  const double* diameter = nullptr;  // m, volume-equivalent sphere diameters of the pivots
  const T* number = nullptr;
  const T* fields[kFields] = {nullptr, nullptr, nullptr, nullptr, nullptr};  // by Field
  const T* field(Field f) const { return fields[static_cast<int>(f)]; }
  // Per-field accessors, as the kernels read them.
  const T* moisture() const { return field(Field::kMoisture); }
  const T* spot_moisture() const { return field(Field::kSpotMoisture); }
  const T* temperature() const { return field(Field::kTemperature); }
  const T* liquid_fraction() const { return field(Field::kLiquidFraction); }
  const T* wetted_fraction() const { return field(Field::kWettedFraction); }
};

// The reference volume of the power-law kernels (sum, product, Kapur; power-law and linear selection). It only
// keeps the rate coefficient in 1/s; v_ref = 1 m^3 with coefficient 1 is the dimensionless textbook form of the
// analytic cases (docs/verification.md).
inline ParamSpec reference_volume_param() {
  return {
      "v_ref", "m3", 1.0, 1e-30, 1e6, "reference volume", "scaling choice; docs/verification.md analytic cases use 1"};
}

class KernelBase {
 public:
  virtual ~KernelBase() = default;
  virtual std::vector<ParamSpec> params() const { return {}; }
  virtual ClassNeeds needs() const { return {}; }
  bool state_dependent() const { return needs().any(); }
  // Structure choices of the kernel (e.g. which data table), read from the owning unit's settings with names
  // prefixed by `prefix`. Called once, while the unit declares itself.
  virtual void declare(Settings& /*settings*/, const std::string& /*prefix*/) {}
  // Checks what the parameter bounds alone cannot (sums, table shapes) before a run; throws ConfigError naming
  // `where`, the value and the rule.
  virtual void check(const ClassState<double>& /*s*/, const double* /*p*/, const std::string& /*where*/) const {}
};

}  // namespace granuflow::kernels
