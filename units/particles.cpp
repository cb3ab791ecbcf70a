#include "particles.hpp"

#include <cctype>
#include <cmath>
#include <string>
#include <utility>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/paper001_defaults.hpp"

namespace granuflow::units {

namespace {
std::string join_components(const ParticleParams& pp) {
  std::string all;
  for (const auto& c : pp.components) all += (all.empty() ? "" : ", ") + c;
  return all;
}

// n >= 2 diameters from lo to hi (both included), equally spaced in ln d.
std::vector<double> log_spaced(double lo, double hi, int n) {
  std::vector<double> d(n);
  for (int i = 0; i < n; ++i) d[i] = lo * std::pow(hi / lo, double(i) / (n - 1));
  return d;
}
}  // namespace

void ParticleSystem::declare(UnitSpec& s, Settings& st) {
  namespace def = kernels::paper001::defaults;
  const std::string kind =
      st.get_choice("grid", "log_diameter", {"log_diameter", "geometric"},
                    "log-spaced diameter pivots (paper 001, Table 5) or geometric in volume with ratio 2^(1/q)");
  if (kind == "log_diameter") {
    const long n = st.get_int("classes", def::kSizeClasses, 3, 2000, "size classes (pivots log-spaced in diameter)");
    const double lo = st.get_real("d_min", def::kDiameterMin, 1e-7, 1e-2, "smallest pivot diameter, m (Table 5)");
    const double hi = st.get_real("d_max", def::kDiameterMax, 1e-7, 1e-1, "largest pivot diameter, m (Table 5)");
    if (!(hi > lo))
      throw ConfigError(violation(st.where() + ".d_max", hi, "m", "d_max > d_min (" + fmt_num(lo) + " m)"));
    grid_ = std::make_shared<const kernels::Grid>(
        kernels::Grid::from_diameter_pivots(log_spaced(lo, hi, static_cast<int>(n))));
  } else {
    const long q = st.get_int("q", 2, 1, 64, "classes per doubling of the particle volume (ratio 2^(1/q))");
    const double v_min = st.get_real("v_min", std::exp2(-12.0), 1e-30, 1e6, "lowest volume edge, m3");
    const long n = st.get_int("classes", 27 * q, 2, 4000, "number of classes");
    grid_ = std::make_shared<const kernels::Grid>(
        kernels::Grid::geometric(v_min, static_cast<int>(q), static_cast<int>(n)));
  }
  water_ = st.get_bool("water", true,
                       "solids streams carry per-class water; false for a dry process (layering without drying, "
                       "sieves, mills): no unit computes water, every stream's water is zero");
  params_.rho_s = s.add_param({"rho_s", "kg/m3", def::kSolidSkeletalDensity, 100.0, 5000.0,
                               "skeletal density of the solid", "paper 001, Table 6"});
  params_.eps_intra = s.add_param({"eps_intra", "-", def::kIntraParticleVoidFraction, 0.0, 0.9,
                                   "intra-particle void fraction", "paper 001, Table 7"});
  params_.rho_p = s.add_param({"rho_p", "kg/m3", def::kParticleDensity, 100.0, 5000.0,
                               "particle density of the closures, Eqs. (33), (42)",
                               "paper 001, Table 9; docs/paper001_decisions.md"});
  params_.cp_s =
      s.add_param({"cp_s", "J/(kg K)", def::kSolidCp, 100.0, 1e4, "heat capacity of the solid", "paper 001, Table 6"});
  declare_components(s, st);
}

// Components after the first: names from the setting (comma- or space-separated), each with its envelope density.
void ParticleSystem::declare_components(UnitSpec& s, Settings& st) {
  namespace def = kernels::paper001::defaults;
  const std::string given = st.get_choice(
      "components", "", {},
      "the named solids a particle is made of, e.g. 'core, layer': the first has rho_s and eps_intra, each further "
      "one its envelope density rho_<name>; per class the mass of each is carried (empty: one solid)");
  std::vector<std::string> names;
  std::string cur;
  for (char ch : given + ",") {
    if (ch == ',' || ch == ' ') {
      if (!cur.empty()) names.push_back(cur), cur.clear();
    } else {
      cur += ch;
    }
  }
  if (names.empty()) return;
  auto bad = [&](const std::string& why) { throw ConfigError(st.where() + ".components = '" + given + "': " + why); };
  if (names.size() < 2 || names.size() > static_cast<size_t>(streams::kMaxComponents))
    bad("give 2 to " + std::to_string(streams::kMaxComponents) + " names (one solid needs no list)");
  for (size_t a = 0; a < names.size(); ++a) {
    for (char ch : names[a])
      if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_')) bad("names are letters, digits and _");
    for (size_t b = 0; b < a; ++b)
      if (names[a] == names[b]) bad("'" + names[a] + "' is named twice");
  }
  params_.components = names;
  for (size_t c = 1; c < names.size(); ++c)
    params_.rho.push_back(s.add_param({"rho_" + names[c], "kg/m3", def::kSolidSkeletalDensity, 100.0, 5000.0,
                                       "envelope density of the component " + names[c],
                                       "user (the default is paper 001's rho_s, Table 6)"}));
}

int ParticleParams::component(const std::string& name) const {
  for (size_t c = 0; c < components.size(); ++c)
    if (components[c] == name) return static_cast<int>(c);
  return -1;
}

const ParticleSystem& particle_system(UnitSpec& s, Settings& st, bool composed) {
  const std::string name =
      st.get_choice("particles", "particles", {}, "the particle system (size grid, product properties) used");
  const UnitInstance* inst = st.unit(name);
  const auto* ps = inst ? dynamic_cast<const ParticleSystem*>(inst->unit.get()) : nullptr;
  if (!ps)
    throw ConfigError(st.where() + ".particles = '" + name +
                      "': no particle system of that name; declare the size grid and product once in the scene's "
                      "`particles:` section (settings: grid, classes, d_min, d_max; params: rho_s, eps_intra, ...)");
  if (!composed && ps->params().component_count() > 1)
    throw ConfigError(st.where() + ": the particle system '" + name +
                      "' is made of several solids (components: " + join_components(ps->params()) +
                      ") and this unit carries one solid only; the units that carry composition are granulator, "
                      "spray_compartment, drying_compartment, solids_feed, sieve, mill, solids_mixer, "
                      "solids_splitter and solids_product");
  s.use_shared_params(name);
  return *ps;
}

void forward_dry_water(UnitSpec& s, PortId out, PortId in, int classes) {
  for (int i = 0; i < classes; ++i) s.forward(out, solids::water(classes, i), in, solids::water(classes, i));
}

void SolidsOutlets::declare(UnitSpec& s, const ParticleSystem& ps, PortId in, const std::vector<std::string>& names) {
  const int n = ps.grid()->size(), K = ps.params().component_count();
  count = static_cast<int>(names.size());
  wet = ps.water();
  for (int o = 0; o < count; ++o) {
    m[o] = s.add_states(names[o] + "_mdot", n, StateKind::Algebraic, "kg/s", 1e-2);
    if (wet) w[o] = s.add_states(names[o] + "_water", n, StateKind::Algebraic, "kg/s", 1e-3);
    for (int k = 1; k < K; ++k)
      q[o].push_back(s.add_states(names[o] + "_" + ps.params().components[k], n, StateKind::Algebraic, "kg/s", 1e-2));
  }
  s.set_explicit();
  const auto& d = ps.grid()->diameter_pivots();
  s.set_port_grid(in, d);
  for (int o = 0; o < count; ++o) {
    const PortId out = s.add_port(names[o], streams::solids(K), PortDir::Out, n);
    s.set_port_grid(out, d);
    for (int i = 0; i < n; ++i) {
      s.provide(out, solids::mdot(i), m[o] + i);
      if (wet) s.provide(out, solids::water(n, i), w[o] + i);
    }
    if (!wet) forward_dry_water(s, out, in, n);
    s.forward(out, solids::T(n), in, solids::T(n));
    for (int k = 1; k < K; ++k)
      for (int i = 0; i < n; ++i) s.provide(out, solids::component(n, k, i), q[o][k - 1] + i);
  }
  ClassLayout layout{n, {}, {{in, solids::mdot(0)}}};
  for (int o = 0; o < count; ++o) {
    layout.state_blocks.push_back(m[o]);
    if (wet) layout.state_blocks.push_back(w[o]);
  }
  if (wet) layout.field_blocks.push_back({in, solids::water(n, 0)});
  for (int k = 1; k < K; ++k) {
    for (int o = 0; o < count; ++o) layout.state_blocks.push_back(q[o][k - 1]);
    layout.field_blocks.push_back({in, solids::component(n, k, 0)});
  }
  s.set_classes(layout);
}

void require_water(const ParticleSystem& ps, const Settings& st, const std::string& what) {
  if (!ps.water())
    throw ConfigError(st.where() + ": " + what +
                      ", but the particle system is dry (particles: settings: water: "
                      "false); set water: true, or leave this unit out");
}

std::vector<FieldSpec> holdup_field_specs(int classes, FieldSpec last) {
  std::vector<FieldSpec> f;
  append_class_fields(f, "mass", classes, "kg");
  append_class_fields(f, "water", classes, "kg");
  f.push_back({"T", "K"});
  f.push_back(std::move(last));
  return f;
}

void register_particles(Registry<Unit>& r) {
  r.add("particles", "the flowsheet's size grid and product properties, shared by every particle unit",
        [] { return std::make_unique<ParticleSystem>(); });
}

}  // namespace granuflow::units
