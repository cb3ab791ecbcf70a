// Declaration of the constant-volume Monte Carlo of spray fluidized-bed agglomeration (paper 003, section 7.7,
// Eqs. (7.48)-(7.58); docs/monte_carlo.md): its parameters (SI unit, bounds, source), its settings (the open points of
// the section, each a named choice) and the quantities derived from them once per run.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "granuflow/param.hpp"

namespace granuflow::montecarlo {

enum class Collisions { kEq748, kConstantKernel };
enum class TimeStep { kPerParticle, kLiteral };
enum class Waiting { kFixed, kExponential };
enum class Success { kPhysics, kConstant };
enum class StokesLength { kRadius, kDiameter };
enum class WetUntil { kAsperity, kWaterGone };

struct Params {
  double F_coll, u0, eps, eps_mf;                            // Eq. (7.48)
  double m_spray, M_bed, rho_p0, rho_l, d0, d_d;             // Eq. (7.51)
  double theta;                                              // Eqs. (7.53)-(7.54)
  double rho_g, rho_w, M_w, M_g, beta, p_sat, p_total, y_v;  // Eq. (7.55)
  double eps_p, r_pore, sigma;                               // Eq. (7.56)
  double mu_l, mu_exponent, u_coll, e, h_a;                  // Eqs. (7.57)-(7.58)
  double eps_agg, K_max;                                     // section 7.7.2, agglomerate structure
  double p_success, beta0, c0;                               // verification modes (docs/verification.md)
};

struct Settings {
  Collisions collisions = Collisions::kEq748;
  TimeStep time_step = TimeStep::kPerParticle;
  Waiting waiting = Waiting::kFixed;
  Success success = Success::kPhysics;
  StokesLength stokes_length = StokesLength::kRadius;
  WetUntil wet_until = WetUntil::kAsperity;
  bool drying = true, imbibition = false;
  long sample_size = 2000;  // N_p,0
  long replicas = 16;
  long threads = 0;  // 0: the machine's
  uint64_t seed = 1;
  long max_droplets = 20000000;  // per replica: beyond it a run stops with an error instead of exhausting memory
};

// Per-run constants of the equations, from the parameters.
struct Derived {
  double f_coll;       // collisions per particle and second, Eq. (7.48)
  double gamma;        // droplets per primary particle and second, Eq. (7.51)
  double V_drop;       // droplet volume, m3
  double h0;           // initial cap height, Eqs. (7.53)-(7.54)
  double area_per_h2;  // base area / h^2 of a cap at the contact angle, pi (sin / (1 - cos))^2
  double k_dry;        // drying rate of the height, m/s, Eq. (7.55)
  double k_imb;        // imbibition coefficient of the height, m/s^0.5, Eq. (7.56)
  double h_end;        // height at which a droplet stops being wet
  double t_life;       // age at which it does (infinite without drying and imbibition)
  double m0;           // primary particle mass, kg
};

struct Config {
  Params p;
  Settings s;
  Derived d;
};

// The declaration table: every parameter (for describe, the docs and validation) and every choice setting.
const std::vector<ParamSpec>& param_specs();
const std::vector<SettingSpec>& setting_specs();

// Parameters by name (SI; missing ones take their defaults) and settings by name (choices as text, counts as
// numbers). Anything unknown or out of bounds is a ConfigError of one line naming it, its value and what is allowed.
Config make_config(const std::map<std::string, double>& params, const std::map<std::string, std::string>& settings);

// Agglomerate diameter of n primaries at constant porosity (section 7.7.2); a single primary keeps d0.
double agglomerate_diameter(const Params& p, double n);

}  // namespace granuflow::montecarlo
