#include "mc_params.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include "granuflow/errors.hpp"

namespace granuflow::montecarlo {
namespace {

constexpr double kPi = 3.14159265358979323846;
const char* const kUser = "user choice (paper 003 prints no value)";
const char* const kEq748 =
    "user choice: with eps = 0.6 and eps_mf = 0.4, Eq. (7.48) gives the f_coll = 1.6 1/s paper 003 quotes for glass "
    "(section 7.7.3)";

struct Entry {
  ParamSpec spec;
  double Params::*member;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = {
      {{"F_coll", "1/m", 10.0, 0.0, 1e4, "collision frequency pre-factor, Eq. (7.48)",
        "paper 003, section 7.7.3: 10 1/m glass, 45 1/m gamma-alumina"},
       &Params::F_coll},
      {{"u0", "m/s", 1.08, 1e-4, 50.0, "fluidization gas velocity, Eq. (7.48)", kEq748}, &Params::u0},
      {{"eps", "-", 0.6, 0.0, 0.9999, "porosity of the expanded bed, Eq. (7.48)", kEq748}, &Params::eps},
      {{"eps_mf", "-", 0.4, 0.0, 0.9999, "porosity at minimum fluidization, Eq. (7.48)", kEq748}, &Params::eps_mf},
      {{"m_spray", "kg/s", 20e-3 / 60, 0.0, 10.0, "mass flow rate of sprayed liquid, Eq. (7.51)",
        "user choice (paper 003, Fig. 7.64 varies it; no value printed)"},
       &Params::m_spray},
      {{"M_bed", "kg", 0.5, 1e-6, 1e5, "bed mass, Eq. (7.51)", kUser}, &Params::M_bed},
      {{"rho_p0", "kg/m3", 2500.0, 100.0, 2e4, "density of the primary particles, Eqs. (7.51), (7.57)",
        "user choice: soda-lime glass (paper 003 prints none)"},
       &Params::rho_p0},
      {{"rho_l", "kg/m3", 1000.0, 100.0, 5000.0, "density of the sprayed liquid, Eq. (7.51)",
        "user choice: a dilute aqueous binder solution, taken as water"},
       &Params::rho_l},
      {{"d0", "m", 0.4e-3, 1e-7, 0.1, "primary particle diameter, Eq. (7.51)",
        "paper 003, section 7.7.3: 0.4 mm glass, 0.36 mm gamma-alumina"},
       &Params::d0},
      {{"d_d", "m", 60e-6, 1e-8, 1e-2, "droplet diameter, Eq. (7.51)", kUser}, &Params::d_d},
      {{"theta", "rad", 0.6981317007977318, 0.01, 3.1, "solid-liquid contact angle (40 deg), Eqs. (7.53)-(7.56)",
        kUser},
       &Params::theta},
      {{"rho_g", "kg/m3", 1.0, 1e-3, 100.0, "gas density, Eq. (7.55)", kUser}, &Params::rho_g},
      {{"rho_w", "kg/m3", 1000.0, 500.0, 2000.0, "density of the solvent (water), Eq. (7.55)", "water"},
       &Params::rho_w},
      {{"M_w", "kg/mol", 0.018015, 1e-3, 1.0, "molar mass of the solvent (water), Eq. (7.55)",
        "IUPAC standard atomic weights"},
       &Params::M_w},
      {{"M_g", "kg/mol", 0.028965, 1e-3, 1.0, "molar mass of the gas (dry air), Eq. (7.55)",
        "ISO 2533 standard atmosphere"},
       &Params::M_g},
      {{"beta", "m/s", 0.05, 0.0, 10.0, "gas-side mass transfer coefficient, Eq. (7.55)", kUser}, &Params::beta},
      {{"p_sat", "Pa", 7384.0, 0.0, 1e7, "saturation pressure of the solvent at the surface, Eq. (7.55)",
        "user choice: water at 40 degC (steam tables: 7.384 kPa)"},
       &Params::p_sat},
      {{"p_total", "Pa", 101325.0, 1e3, 1e7, "gas pressure, Eq. (7.55)", "user choice: one standard atmosphere"},
       &Params::p_total},
      {{"y_v", "-", 0.01, 0.0, 1.0, "molar fraction of solvent vapour in the gas, Eq. (7.55)", kUser}, &Params::y_v},
      {{"eps_p", "-", 0.5, 0.0, 0.99, "porosity of the primary particles (imbibition: on), Eq. (7.56)", kUser},
       &Params::eps_p},
      {{"r_pore", "m", 5e-9, 1e-10, 1e-3, "pore radius of the primary particles (imbibition: on), Eq. (7.56)", kUser},
       &Params::r_pore},
      {{"sigma", "N/m", 0.072, 1e-3, 1.0, "surface tension of the liquid, Eq. (7.56)", "water at 25 degC"},
       &Params::sigma},
      {{"mu_l", "Pa s", 0.05, 1e-5, 1e5, "viscosity of the sprayed liquid, Eqs. (7.56)-(7.57)",
        "user choice (paper 003, Fig. 7.65 varies it through the binder fraction; no value printed)"},
       &Params::mu_l},
      {{"mu_exponent", "-", 0.0, 0.0, 10.0,
        "rise of the droplet's viscosity as it dries, mu = mu_l (V0 / V)^mu_exponent (0: none)",
        "user choice: paper 003, section 7.7.3.2 states the rise but gives no law"},
       &Params::mu_exponent},
      {{"u_coll", "m/s", 0.5, 0.0, 100.0, "collision velocity, Eq. (7.57)", kUser}, &Params::u_coll},
      {{"e", "-", 0.8, 1e-3, 1.0, "coefficient of restitution, Eq. (7.58)",
        "paper 003, section 7.5.4 (gamma-alumina, measured)"},
       &Params::e},
      {{"h_a", "m", 1e-6, 1e-10, 1e-3, "height of the surface asperities, Eq. (7.58)", kUser}, &Params::h_a},
      {{"eps_agg", "-", 0.6, 0.0, 0.95, "agglomerate porosity (diameter from the primaries)",
        "paper 003, section 7.7.2 (60 %)"},
       &Params::eps_agg},
      {{"K_max", "-", 6.0, 1.0, 12.0, "maximum coordination number of a primary particle", "paper 003, section 7.7.2"},
       &Params::K_max},
      {{"p_success", "-", 1.0, 0.0, 1.0, "probability that a collision agglomerates (success: constant)",
        "verification (docs/verification.md)"},
       &Params::p_success},
      {{"beta0", "m3/s", 1.0, 0.0, 1e30, "constant aggregation kernel (collisions: constant_kernel)",
        "verification (docs/verification.md)"},
       &Params::beta0},
      {{"c0", "1/m3", 1.0, 1e-30, 1e30, "initial number concentration (collisions: constant_kernel)",
        "verification (docs/verification.md)"},
       &Params::c0},
  };
  return e;
}

SettingSpec choice(const std::string& name, const std::vector<std::string>& choices, const std::string& what) {
  return {name, SettingType::String, choices.front(), choices, -1e300, 1e300, what, ""};
}
SettingSpec count(const std::string& name, long value, double lo, double hi, const std::string& what) {
  return {name, SettingType::Int, value, {}, lo, hi, what, ""};
}

std::string setting_text(const std::map<std::string, std::string>& s, const SettingSpec& spec) {
  auto it = s.find(spec.name);
  return it == s.end() ? setting_to_string(spec.value) : it->second;
}

long setting_count(const std::map<std::string, std::string>& s, const SettingSpec& spec) {
  const std::string text = setting_text(s, spec);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || v != std::floor(v) || v < spec.lower || v > spec.upper)
    throw ConfigError("monte_carlo setting " + spec.name + " = '" + shown(text) + "': expected a whole number in [" +
                      fmt_num(spec.lower) + ", " + fmt_num(spec.upper) + "]");
  return static_cast<long>(v);
}

int setting_choice(const std::map<std::string, std::string>& s, const SettingSpec& spec) {
  const std::string text = setting_text(s, spec);
  std::string allowed;
  for (size_t k = 0; k < spec.choices.size(); ++k) {
    if (spec.choices[k] == text) return static_cast<int>(k);
    allowed += (k ? ", " : "") + spec.choices[k];
  }
  throw ConfigError("monte_carlo setting " + spec.name + " = '" + shown(text) + "': allowed are " + allowed);
}

Derived derive(const Params& p, const Settings& s) {
  Derived d{};
  const double ratio = (1.0 - p.eps) / (1.0 - p.eps_mf);
  d.f_coll = p.F_coll * (1.0 - ratio) * ratio * ratio * p.u0;                      // Eq. (7.48)
  d.gamma = p.m_spray / p.M_bed * p.rho_p0 / p.rho_l * std::pow(p.d0 / p.d_d, 3);  // Eq. (7.51)
  d.V_drop = kPi / 6.0 * p.d_d * p.d_d * p.d_d;
  const double c = std::cos(p.theta), sn = std::sin(p.theta);
  const double a = std::cbrt(3.0 * d.V_drop / kPi * sn * sn * sn / (2.0 - 3.0 * c + c * c * c));  // Eq. (7.53)
  d.h0 = a * (1.0 - c) / sn;                                                                      // Eq. (7.54)
  d.area_per_h2 = kPi * (sn / (1.0 - c)) * (sn / (1.0 - c));
  const double shape = 1.0 / (1.0 / (1.0 - c) - 1.0 / 3.0);
  d.k_dry = s.drying ? 2.0 / 3.0 * p.rho_g / p.rho_w * p.M_w / p.M_g * p.beta / (1.0 - c) *
                           (p.p_sat / p.p_total - p.y_v) * shape  // Eq. (7.55)
                     : 0.0;
  d.k_imb = s.imbibition ? 2.0 / 3.0 * p.eps_p * (sn / (1.0 - c)) * (sn / (1.0 - c)) * shape *
                               std::sqrt(p.sigma * c * p.r_pore / (8.0 * p.mu_l))  // Eq. (7.56)
                         : 0.0;
  d.h_end = s.wet_until == WetUntil::kAsperity ? std::min(p.h_a, d.h0) : 0.0;
  // Age at which h0 - k_dry t - k_imb sqrt(t) reaches h_end: the positive root in sqrt(t).
  const double drop = d.h0 - d.h_end;
  double root = std::numeric_limits<double>::infinity();
  if (d.k_dry > 0.0)
    root = (-d.k_imb + std::sqrt(d.k_imb * d.k_imb + 4.0 * d.k_dry * drop)) / (2.0 * d.k_dry);
  else if (d.k_imb > 0.0)
    root = drop / d.k_imb;
  d.t_life = root * root;
  d.m0 = p.rho_p0 * kPi / 6.0 * p.d0 * p.d0 * p.d0;
  return d;
}

}  // namespace

const std::vector<ParamSpec>& param_specs() {
  static const std::vector<ParamSpec> v = [] {
    std::vector<ParamSpec> out;
    for (const Entry& e : entries()) out.push_back(e.spec);
    return out;
  }();
  return v;
}

const std::vector<SettingSpec>& setting_specs() {
  static const std::vector<SettingSpec> v = {
      choice("collisions", {"eq_7_48", "constant_kernel"},
             "collision rate: each particle collides f_coll times per second (Eq. (7.48)), or the constant kernel "
             "beta0 over every pair of the sample volume (verification)"),
      choice("time_step", {"per_particle", "literal"},
             "Eq. (7.49): t_step = 2 / (f_coll N_p) (f_coll per particle; independent of the sample size) or "
             "t_step = 1 / f_coll for the whole sample (literal; kinetics scale with N_p,0)"),
      choice("waiting_time", {"fixed", "exponential"},
             "time between collisions: the step of Eq. (7.49) itself (Eq. (7.50)), or exponentially distributed "
             "with that mean (the Markov process whose mean is the population balance)"),
      choice("success", {"physics", "constant"},
             "a collision agglomerates when it hits a wet spot and the Stokes criterion holds (Eqs. (7.57)-(7.58)), "
             "or with the constant probability p_success (no droplets; verification)"),
      choice("stokes_length", {"radius", "diameter"},
             "length in Eq. (7.57): the harmonic-mean radius (Ennis et al. 1991) or the diameter as printed "
             "(St_coal four times smaller)"),
      choice("wet_until", {"asperity", "water_gone"},
             "a droplet stops being wet when its height falls to h_a, or when its liquid is gone (h = 0)"),
      choice("drying", {"on", "off"}, "droplets age by drying, Eq. (7.55)"),
      choice("imbibition", {"off", "on"}, "droplets age by imbibition into porous primaries, Eq. (7.56)"),
      count("sample_size", 2000, 2, 1e7, "initial number of primary particles in the sample, N_p,0"),
      count("replicas", 16, 2, 1e5, "independent replicas (confidence intervals over them)"),
      count("threads", 0, 0, 1024, "threads running replicas (0: one per core); results do not depend on it"),
      count("seed", 1, 0, 9007199254740992.0, "seed; replica i draws from (seed, i)"),
      count("max_droplets", 20000000, 1000, 2e9,
            "droplets one replica may hold (12 bytes each); a run that needs more stops with an error"),
  };
  return v;
}

Config make_config(const std::map<std::string, double>& params, const std::map<std::string, std::string>& settings) {
  Config c{};
  for (const Entry& e : entries()) c.p.*e.member = e.spec.value;
  for (const auto& [name, value] : params) {
    const Entry* hit = nullptr;
    std::string known;
    for (const Entry& e : entries()) {
      if (e.spec.name == name) hit = &e;
      known += (known.empty() ? "" : ", ") + e.spec.name;
    }
    if (!hit) throw ConfigError("monte_carlo parameter '" + shown(name) + "' is not known; known: " + known);
    if (!std::isfinite(value) || value < hit->spec.lower || value > hit->spec.upper)
      throw ConfigError("monte_carlo parameter " + name + " = " + fmt_num(value) + " " + hit->spec.unit +
                        ": allowed is [" + fmt_num(hit->spec.lower) + ", " + fmt_num(hit->spec.upper) + "]");
    c.p.*hit->member = value;
  }
  for (const auto& [name, value] : settings) {
    bool found = false;
    std::string known;
    for (const SettingSpec& s : setting_specs()) {
      found = found || s.name == name;
      known += (known.empty() ? "" : ", ") + s.name;
    }
    if (!found) throw ConfigError("monte_carlo setting '" + shown(name) + "' is not known; known: " + known);
  }
  const auto& ss = setting_specs();
  c.s.collisions = static_cast<Collisions>(setting_choice(settings, ss[0]));
  c.s.time_step = static_cast<TimeStep>(setting_choice(settings, ss[1]));
  c.s.waiting = static_cast<Waiting>(setting_choice(settings, ss[2]));
  c.s.success = static_cast<Success>(setting_choice(settings, ss[3]));
  c.s.stokes_length = static_cast<StokesLength>(setting_choice(settings, ss[4]));
  c.s.wet_until = static_cast<WetUntil>(setting_choice(settings, ss[5]));
  c.s.drying = setting_choice(settings, ss[6]) == 0;
  c.s.imbibition = setting_choice(settings, ss[7]) == 1;
  c.s.sample_size = setting_count(settings, ss[8]);
  c.s.replicas = setting_count(settings, ss[9]);
  c.s.threads = setting_count(settings, ss[10]);
  c.s.seed = static_cast<uint64_t>(setting_count(settings, ss[11]));
  c.s.max_droplets = setting_count(settings, ss[12]);
  if (c.p.eps < c.p.eps_mf)
    throw ConfigError("monte_carlo parameter eps = " + fmt_num(c.p.eps) + " is below eps_mf = " + fmt_num(c.p.eps_mf) +
                      ": an expanded bed is at least as porous as at minimum fluidization (Eq. (7.48))");
  c.d = derive(c.p, c.s);
  if (c.s.collisions == Collisions::kEq748 && !(c.d.f_coll > 0.0))
    throw ConfigError("monte_carlo: Eq. (7.48) gives no collisions (f_coll = " + fmt_num(c.d.f_coll) +
                      " 1/s); F_coll and u0 must be positive and eps above eps_mf");
  return c;
}

double agglomerate_diameter(const Params& p, double n) {
  return n <= 1.0 ? p.d0 : p.d0 * std::cbrt(n / (1.0 - p.eps_agg));
}

}  // namespace granuflow::montecarlo
