// The particle system of a flowsheet: one size grid and one set of product properties, declared once and shared by
// every unit that holds or moves particles (scene key `particles:`; units find it by its instance name, setting
// `particles`, default "particles"). Grid: paper 001's log-spaced diameter pivots (Table 5: 10 classes, 50-1000 um)
// or a geometric grid in volume (ratio 2^(1/q), Kumar & Ramkrishna 1996) for verification. Properties: skeletal
// density and intra-particle porosity (the envelope density rho_s (1 - eps) relates size and mass), the particle
// density of paper 001's closures (Table 9) and the solid heat capacity.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "granuflow/registry.hpp"
#include "granuflow/unit.hpp"
#include "kernels/discretization/grid.hpp"

namespace granuflow::units {

struct ParticleParams {
  ParamId rho_s, eps_intra, rho_p, cp_s;
  // The named solids a particle is made of (setting `components`; one, "solid", by default): the first has the
  // envelope density rho_s (1 - eps_intra), each further one c its own envelope density rho_<name> (rho[c - 1]).
  std::vector<std::string> components{"solid"};
  std::vector<ParamId> rho;
  // Envelope density rho_s (1 - eps_intra), kg/m3, from the particle system's parameters `shared`.
  template <class T>
  T envelope_density(const T* shared) const {
    return shared[rho_s.i] * (1.0 - shared[eps_intra.i]);
  }
  int component_count() const { return static_cast<int>(components.size()); }
  // Envelope density of component c, kg/m3.
  template <class T>
  T component_density(const T* shared, int c) const {
    return c == 0 ? envelope_density(shared) : T(shared[rho[c - 1].i]);
  }
  // Index of the component `name`, or -1.
  int component(const std::string& name) const;
};

class ParticleSystem : public UnitBase<ParticleSystem> {
 public:
  std::string type() const override { return "particles"; }
  void declare(UnitSpec& s, Settings& st) override;
  template <class T>
  Status eval(const Ctx<T>&) const {
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>&) const {}
  std::shared_ptr<const kernels::Grid> grid() const { return grid_; }
  const ParticleParams& params() const { return params_; }
  // False for a dry process (setting `water: false`): no unit holds or moves water, and the water fields of every
  // solids stream are the one zero of the unit the stream starts from, passed on unchanged (forward_dry_water).
  bool water() const { return water_; }

 private:
  void declare_components(UnitSpec& s, Settings& st);
  std::shared_ptr<const kernels::Grid> grid_;
  ParticleParams params_;
  bool water_ = true;
};

// The particle system a unit uses (setting `particles` names the instance); marks the unit as reading its
// parameters (Ctx::sh). ConfigError naming the unit when the flowsheet declares none, or when the system names
// several solids (components) and the unit does not carry composition (`composed` false).
const ParticleSystem& particle_system(UnitSpec& s, Settings& st, bool composed = false);

void register_particles(Registry<Unit>& r);

// In a dry particle system, the outlet `out`'s per-class water fields pass on those of the inlet `in` (both solids
// streams): a unit that splits, mills or mixes dry solids computes no water.
void forward_dry_water(UnitSpec& s, PortId out, PortId in, int classes);
// The outlets of a zero-hold-up solids unit that splits its inlet (sieve, splitter): per outlet named `names[o]`,
// algebraic states for the flow of solids, of water (wet systems) and of each named solid after the first, one solids
// port, and the class layout that keeps every class's states together. The temperature passes through.
struct SolidsOutlets {
  static constexpr int kMax = 3;
  int count = 0;
  bool wet = true;
  StateId m[kMax], w[kMax];
  std::vector<StateId> q[kMax];  // q[o][k - 1]: named solid k (k >= 1) of outlet o
  // Declares the states (then marks the unit explicit), the ports on the inlet's grid and the class layout.
  void declare(UnitSpec& s, const ParticleSystem& ps, PortId in, const std::vector<std::string>& names);
  template <class T>
  void init(InitCtx<T>& c, int classes) const {
    for (int o = 0; o < count; ++o)
      for (int i = 0; i < classes; ++i) {
        c.x(m[o] + i) = T(0.0);
        if (wet) c.x(w[o] + i) = T(0.0);
        for (StateId s : q[o]) c.x(s + i) = T(0.0);
      }
  }
};
// ConfigError naming the unit when it holds or moves water (`what`) in a dry particle system.
void require_water(const ParticleSystem& ps, const Settings& st, const std::string& what);

// A particle hold-up as another unit reads it (a bed's for its spray zone, a chamber's for its outlets): per class
// dry-solid and water mass (kg), the temperature (K), then one scalar the stream kind names.
std::vector<FieldSpec> holdup_field_specs(int classes, FieldSpec last);
namespace holdup_layout {
inline int mass(int i) { return i; }
inline int water(int classes, int i) { return classes + i; }
inline int T(int classes) { return 2 * classes; }
inline int last(int classes) { return 2 * classes + 1; }
}  // namespace holdup_layout

}  // namespace granuflow::units
