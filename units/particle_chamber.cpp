#include "particle_chamber.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>

#include "chamber_outlet.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/paper001_defaults.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/registry.hpp"

namespace granuflow::units {

using kernels::Field;

struct ParticleChamber::Work : Workspace {
  kernels::Population::WorkPtr pop;
  // particle mass, surface per mass and the number floor kMassFloor / m of each class at the run's parameters
  std::vector<double> pm, spm, floor;
  Classifier::Cache cls;
  template <class T>
  struct Scratch {
    std::vector<T> pm, spm, N, floor, dM, dW, dN, F, ones, temp, in_m, in_w, gather;
    std::vector<int> donor;
    void resize(int n) {
      for (auto* v : {&pm, &spm, &N, &floor, &dM, &dW, &dN, &temp, &in_m, &in_w}) v->assign(n, T(0.0));
      F.assign(n + 1, T(0.0)), ones.assign(n + 1, T(1.0)), donor.assign(n + 1, -1);
    }
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  std::vector<double> dF;        // growth flux Jacobian, (n + 1) x n
  kernels::Population::Map map;  // the engine's inputs and rates in the unit's Jacobian (built on first use)
  bool mapped = false;
};

namespace {

const char* role_type(ChamberRole r) {
  switch (r) {
    case ChamberRole::kSprayZone:
      return "spray_compartment";
    case ChamberRole::kDryingZone:
      return "drying_compartment";
    default:
      return "granulator";
  }
}

// (u + sqrt(u^2 + eps^2)) / 2: a valve that cannot run backwards, smooth for Newton and the integrator.
template <class T>
T softplus(const T& u, const T& eps) {
  using std::sqrt;
  return 0.5 * (u + sqrt(u * u + eps * eps));
}

constexpr double kValveSmoothing = 1e-3;  // eps = kValveSmoothing M_set / tau_c

}  // namespace

std::string ParticleChamber::type() const { return role_type(role_); }

void ParticleChamber::declare(UnitSpec& s, Settings& st) {
  const ParticleSystem& ps = particle_system(s, st);
  pp_ = ps.params();
  grid_ = ps.grid();
  n_ = grid_->size();
  const std::string p3 = "paper 003, section 7.5", op = "operating input", init = "initial state (user)";
  spray_ = role_ != ChamberRole::kDryingZone;
  if (role_ == ChamberRole::kGranulator)
    spray_ = st.get_choice("spray", "layering", {"layering", "none"},
                           "layering growth from the spray (paper 003, Eq. (7.33)) or no spray (a drying or "
                           "residence-time segment)") == "layering";
  wet_ = st.get_choice("drying", "none", {"none", "first_order"},
                       "water on the particles: none (sprayed and fed water evaporates at once) or per-class water "
                       "drying at (W - X_eq M) / tau_dry") == "first_order";
  if (wet_) require_water(ps, st, "drying: first_order keeps per-class water on the particles");
  if (role_ != ChamberRole::kSprayZone) {
    const std::string d = st.get_choice("discharge", role_ == ChamberRole::kGranulator ? "unclassified" : "none",
                                        {"none", "unclassified", "classified"},
                                        "product discharge: none (batch), well mixed, or classified by a separation "
                                        "curve (a sifter or counter-current discharge tube)");
    discharge_ = d == "none" ? Discharge::kNone : d == "classified" ? Discharge::kClassified : Discharge::kUnclassified;
    if (discharge_ != Discharge::kNone)
      controlled_ = st.get_choice("bed_mass", "free", {"free", "controlled"},
                                  "hold-up: free (discharge rate k_discharge per second) or held at M_set by the "
                                  "discharge (ideal level controller)") == "controlled";
  }
  p_mass_ = s.add_param(
      {"bed_mass", "kg", role_ == ChamberRole::kSprayZone ? 0.08 : 4.0, 0.0, 1e5, "initial dry solids hold-up", init});
  p_d50_ = s.add_param({"d50_0", "m", 1.8e-3, 1e-7, 1.0, "initial mass median diameter (log-normal in mass)", init});
  p_sigma_ = s.add_param({"sigma_0", "-", 1.15, 1.001, 10.0, "initial geometric standard deviation", init});
  p_t_ = s.add_param({"T_bed", "K", 353.15, 250.0, 700.0, "bed temperature (held by the gas)", "paper 003, Table 7.7"});
  p_cpl_ = s.add_param({"cp_l", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 100.0, 1e4,
                        "heat capacity of water and spray liquid", "paper 001, Table 6"});
  if (spray_) {
    p_spray_ = s.add_param({"m_spray", "kg/s", 112e-3 / 60.0, 0.0, 1e3, "spray liquid mass flow",
                            "paper 003, Table 7.7 (100 ml/min at an assumed 1.12 kg/L)"});
    p_w_ = s.add_param(
        {"w_spray", "kg/kg", 0.3, 0.0, 1.0, "solids mass fraction of the spray liquid", "paper 003, Table 7.7"});
    p_tspray_ = s.add_param({"T_spray", "K", 293.15, 250.0, 400.0, "spray liquid temperature", op});
  }
  if (wet_) {
    p_x0_ = s.add_param({"X0", "kg/kg", 0.0, 0.0, 10.0, "initial moisture, dry basis", init});
    p_taudry_ = s.add_param({"tau_dry", "s", 60.0, 1e-3, 1e7, "drying time constant of the particle water", op});
    p_xeq_ = s.add_param({"X_eq", "kg/kg", 0.0, 0.0, 1.0, "equilibrium moisture, dry basis", op});
  }
  if (role_ != ChamberRole::kGranulator)
    p_tau_ = s.add_param({"tau", "s", role_ == ChamberRole::kSprayZone ? 4.0 : 196.0, 1e-3, 1e7,
                          "mean residence time of a particle in this compartment, Eqs. (7.37)-(7.39)",
                          "paper 003, Table 7.7"});
  if (discharge_ != Discharge::kNone && !controlled_)
    p_k_ = s.add_param({"k_discharge", "1/s", 1e-3, 0.0, 10.0,
                        discharge_ == Discharge::kClassified
                            ? "discharge rate of the particles the classifier passes: fraction per second"
                            : "discharge rate: fraction of the hold-up leaving per second",
                        op});
  if (controlled_) {
    p_mset_ = s.add_param({"M_set", "kg", 4.0, 1e-6, 1e5, "set point of the dry bed mass", op});
    p_tauc_ = s.add_param(
        {"tau_c", "s", 60.0, 1e-3, 1e6, "time constant of the discharge controller's correction (M - M_set)", op});
    p_rmax_ = s.add_param({"mdot_max", "kg/s", 1e3, 1e-9, 1e6, "capacity of the discharge (valve fully open)", op});
  }
  if (discharge_ == Discharge::kClassified)
    classifier_.declare(s, st, "classifier", "plitt", "class_", "separation curve of the classifying discharge", grid_,
                        1e-3);

  // Aggregation and breakage by the engine (growth is the unit's own layering); particles leaving the grid stay
  // in the end classes.
  kernels::PopulationOptions o;
  o.growth = "";
  o.outside = kernels::Outside::kFold;
  if (wet_) o.properties = {"water"};
  pop_.declare(s, st, grid_, o);
  if (pop_.outside() != kernels::Outside::kFold)
    throw ConfigError(st.where() +
                      ".outside = remove: a chamber keeps particles leaving the grid in its end classes "
                      "(outside: fold), so that its balances close");
  for (int f = 0; f < kernels::kFields; ++f)
    if (static_cast<Field>(f) != Field::kTemperature && pop_.needs().field(static_cast<Field>(f)))
      throw ConfigError(st.where() + ": the chamber supplies its kernels the bed temperature only, not the " +
                        std::string(kernels::field_name(static_cast<Field>(f))));
  if (pop_.needs().number)
    throw ConfigError(st.where() + ": kernels that read particle numbers are not supported in the chamber units");
  if (spray_) {
    const auto& reg = kernels::registries().growth_schemes;
    fv_ = reg.create(st.get_choice("growth_scheme", "fv_van_albada", reg.names(),
                                   "finite-volume scheme of the layering (fv_van_albada: smooth, for the integrator)"),
                     st.where());
    fv_->setup(*grid_);
  }

  sM_ = s.add_states("M", n_, StateKind::Differential, "kg", 1.0);
  if (wet_) sW_ = s.add_states("W", n_, StateKind::Differential, "kg", 0.1);
  sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
  if (!wet_) sZero_ = s.add_state("water_out", StateKind::Algebraic, "kg/s", 1e-3);  // dry outlets carry none
  const auto& d = grid_->diameter_pivots();
  auto inlet = [&](const std::string& name, bool optional) {
    const PortId p = s.add_port(name, streams::solids(), PortDir::In, n_, optional);
    s.set_port_grid(p, d);
    inlets_.push_back(p);
  };
  auto outlet = [&](const std::string& name, Outlet& o) {
    o.rate = s.add_state(name + "_rate", StateKind::Algebraic, "1/s", 1e-3);
    o.holdup = s.add_port(name + "_holdup", chamber_holdup(), PortDir::Out, n_);
    s.set_port_grid(o.holdup, d);
    for (int i = 0; i < n_; ++i) {
      s.provide(o.holdup, holdup_fields::mass(i), sM_ + i);
      s.provide(o.holdup, holdup_fields::water(n_, i), wet_ ? sW_ + i : sZero_);
    }
    s.provide(o.holdup, holdup_fields::T(n_), sT_);
    s.provide(o.holdup, holdup_fields::rate(n_), o.rate);
    ChamberOutletSpec spec{n_, wet_,
                           &o == &discharge_out_ && discharge_ == Discharge::kClassified ? &classifier_ : nullptr, d};
    s.add_companion(
        {name, [spec](const std::string& owner) { return make_chamber_outlet(owner, spec); }, o.holdup, name});
  };
  if (role_ != ChamberRole::kGranulator) {
    inlet("in", false);
    outlet("out", exchange_);
  }
  if (role_ != ChamberRole::kSprayZone) inlet("feed", true);
  if (discharge_ != Discharge::kNone) outlet("discharge", discharge_out_);

  ClassLayout layout{n_, {sM_}, {}};
  if (wet_) layout.state_blocks.push_back(sW_);
  for (PortId p : inlets_) {
    layout.field_blocks.push_back({p, solids::mdot(0)});
    if (wet_) layout.field_blocks.push_back({p, solids::water(n_, 0)});
  }
  s.set_classes(layout);
  if (controlled_) {
    r_mass_ = s.add_reduction("hold-up");
    if (discharge_ == Discharge::kClassified) r_tm_ = s.add_reduction("classifier-weighted hold-up");
    r_in_ = s.add_reduction("solids fed");
  }
  if (spray_ && wet_) r_surface_ = s.add_reduction("particle surface");
  if (spray_ || pop_.aggregation() || pop_.breakage()) s.set_analytic_part();  // layering and the engine

  if (spray_) {
    q_solids_in_ = s.add_quadrature("balance_solids_in", "kg", 1.0, OutputRole::kBalanceIn, "solids");
    q_water_in_ = s.add_quadrature("balance_water_in", "kg", 1.0, OutputRole::kBalanceIn, "water");
  }
  q_water_out_ = s.add_quadrature("balance_water_out", "kg", 1.0, OutputRole::kBalanceOut, "water");
  q_energy_in_ = s.add_quadrature("balance_energy_in", "J", 1e6, OutputRole::kBalanceIn, "energy");
  q_energy_out_ = s.add_quadrature("balance_energy_out", "J", 1e6, OutputRole::kBalanceOut, "energy");
  o_mass_ = s.add_output("mass", "kg");
  if (wet_) o_moisture_ = s.add_output("moisture", "kg/kg");
  o_d_[0] = s.add_output("d10", "m");
  o_d_[1] = s.add_output("d50", "m");
  o_d_[2] = s.add_output("d90", "m");
  o_d32_ = s.add_output("d32", "m");
  o_dmean_ = s.add_output("d_mean", "m");
  o_sigma_ = s.add_output("sigma", "m");
  if (spray_) o_g_ = s.add_output("G", "m/s");
  o_particles_ = s.add_output("particles", "-");
  if (discharge_ != Discharge::kNone) o_dis_ = s.add_output("discharge_mdot", "kg/s");
  if (exchange_.rate) o_exch_ = s.add_output("exchange_mdot", "kg/s");
  o_top_ = s.add_output("top_class_fraction", "-", OutputRole::kGridEnd);
  o_heat_ = s.add_output("heat_duty", "W");
  o_vapour_ = s.add_output("vapour_mdot", "kg/s");
  o_hold_solids_ = s.add_output("balance_solids_hold", "kg", OutputRole::kBalanceHold, "solids");
  o_hold_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
  o_hold_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
  std::tie(o_psd_d_, o_psd_m_) = s.add_size_distribution(n_);
}

std::unique_ptr<Workspace> ParticleChamber::workspace() const {
  auto w = std::make_unique<Work>();
  w->pop = pop_.make_work();
  w->sd.resize(n_);
  w->sj.resize(n_);
  return w;
}

void ParticleChamber::configure(const UnitSpec&, const double* p, const double* shared, Workspace& ws) const {
  Work& w = static_cast<Work&>(ws);
  w.pm.resize(n_), w.spm.resize(n_), w.floor.resize(n_);
  const double rho = pp_.envelope_density(shared);
  for (int i = 0; i < n_; ++i) {
    w.pm[i] = rho * grid_->pivot(i);
    w.spm[i] = kernels::sphere_surface(grid_->diameter_pivots()[i]) / w.pm[i];
    w.floor[i] = kMassFloor / w.pm[i];  // an emptied class carries a finite moisture
  }
  pop_.configure(*w.pop, p, std::string("unit ") + type());
  w.cls = {};
  w.mapped = false;
}

void ParticleChamber::check(const UnitSpec&, const double*) const {}

// Particle masses, surfaces per mass and number floors for this evaluation: cached for doubles; Jets recompute them,
// so that sensitivities to the particle system's density carry through.
namespace {
template <class T, class W, class S>
const T* particle_tables(const Ctx<T>& c, const W& w, S& sc, const ParticleParams& pp, const kernels::Grid& g) {
  const int n = g.size();
  if constexpr (std::is_same_v<T, double>) {
    std::copy(w.spm.begin(), w.spm.end(), sc.spm.begin());
    std::copy(w.pm.begin(), w.pm.end(), sc.pm.begin());
    std::copy(w.floor.begin(), w.floor.end(), sc.floor.begin());
  } else {
    const T rho = pp.envelope_density(c.shared);
    for (int i = 0; i < n; ++i) {
      sc.pm[i] = rho * g.pivot(i);
      sc.spm[i] = kernels::sphere_surface(g.diameter_pivots()[i]) / sc.pm[i];
      sc.floor[i] = kMassFloor / sc.pm[i];
    }
  }
  return sc.pm.data();
}
}  // namespace

template <class T>
T ParticleChamber::spray_solids(const Ctx<T>& c) const {
  return spray_ ? T(c.par(p_spray_) * c.par(p_w_)) : T(0.0);
}

template <class T>
void ParticleChamber::inlet_flows(const Ctx<T>& c, T* in_m, T* in_w, std::vector<T>& gather) const {
  std::fill(in_m, in_m + n_, T(0.0));
  std::fill(in_w, in_w + n_, T(0.0));
  for (PortId p : inlets_) {  // inlet by inlet over the classes: plain array loops
    const T* m = c.port_array(p, solids::mdot(0), n_, gather);
    for (int i = 0; i < n_; ++i) in_m[i] += m[i];
    if (!wet_) continue;
    const T* w = c.port_array(p, solids::water(n_, 0), n_, gather);
    for (int i = 0; i < n_; ++i) in_w[i] += w[i];
  }
}

// Paper 003, Eqs. (7.32)-(7.34): the number fluxes F_f through the faces of the cells (fv_growth.hpp), normalized so
// that the created volume is M_sus / rho; in mass, class i gains m_i F_i and loses m_i F_{i+1}; what grows past the
// top face is kept in the top class with its volume (x_hi), so the mass gained is exactly M_sus. Water moves with the
// particles of the donor cell.
template <class T>
void ParticleChamber::growth_rates(const Ctx<T>& c, const T* N, const T* W, const T& amount, T* dM, T* dW) const {
  auto& sc = c.template ws<Work>().template scratch<T>();
  const kernels::GrowthTerms<T> g{1, sc.ones.data(), &amount, true};
  fv_->fluxes(N, g, sc.F.data(), sc.donor.data());
  const T rho = pp_.envelope_density(c.shared);
  const T* pm = sc.pm.data();
  for (int f = 0; f <= n_; ++f) {
    const T& F = sc.F[f];
    if (f > 0) dM[f - 1] -= pm[f - 1] * F;
    if (f < n_)
      dM[f] += pm[f] * F;
    else
      dM[n_ - 1] += rho * grid_->upper_virtual() * F;
    const int d = sc.donor[f];
    if (!W || d < 0 || f == n_) continue;  // water crossing the top face stays in the top class
    const T q = F * W[d] / (N[d] + sc.floor[d]);
    if (f > 0) dW[f - 1] -= q;
    dW[f] += q;
  }
}

template <class T>
kernels::Population::State<T> ParticleChamber::population_state(const Ctx<T>& c, const T* N, const T* floor,
                                                                T* temp) const {
  kernels::Population::State<T> st;
  st.N = N;
  if (wet_) st.q[0] = &c.x(sW_);
  st.floor = floor;
  for (int i = 0; i < n_; ++i) temp[i] = c.x(sT_);
  st.fields[static_cast<int>(Field::kTemperature)] = temp;
  st.p = c.p;
  return st;
}

template <class T>
const T* ParticleChamber::discharge_fractions(const Ctx<T>& c) const {
  if (discharge_ != Discharge::kClassified) return nullptr;
  return classifier_.fractions(c.p, c.template ws<Work>().cls);
}

// What class i carries out through outlet `o`: the flows the outlet's companion computes (chamber_outlet.cpp).
template <class T>
std::pair<T, T> ParticleChamber::outlet_flow(const Ctx<T>& c, const Outlet& o, const T* frac, int i) const {
  const T r = frac ? T(c.x(o.rate) * frac[i]) : c.x(o.rate);
  return {r * c.x(sM_ + i), wet_ ? T(r * c.x(sW_ + i)) : T(0.0)};
}

template <class T>
Status ParticleChamber::eval(const Ctx<T>& c) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.template scratch<T>();
  const T* pm = particle_tables(c, w, sc, pp_, *grid_);
  const T* M = &c.x(sM_);
  const T* W = wet_ ? &c.x(sW_) : nullptr;
  // A class mass far below zero is no state of a bed (a Newton iterate of a steady-state solve that left the physical
  // branch, or an integrator step too long): refuse it, so that the step is cut. The integrator's own round-off in
  // emptied classes stays many orders of magnitude below the threshold.
  double held = 0.0, lowest = 0.0;
  if constexpr (std::is_same_v<T, double>) {  // vectorized: the order of the sum does not matter to the test
    const Eigen::Map<const Eigen::ArrayXd> m(M, n_);
    held = m.abs().sum(), lowest = std::min(0.0, m.minCoeff());
  } else {
    for (int i = 0; i < n_; ++i) held += std::abs(value_of(M[i])), lowest = std::min(lowest, value_of(M[i]));
  }
  if (lowest < -1e-6 * held) return Status::kRecoverable;
  for (int i = 0; i < n_; ++i) {
    sc.N[i] = M[i] / pm[i];
    sc.dM[i] = sc.dW[i] = T(0.0);
  }
  const T m_sus = spray_solids(c);
  if (!c.in_jacobian()) {  // the analytic part covers layering and the engine's mechanisms
    if (spray_) growth_rates(c, sc.N.data(), W, T(m_sus / pp_.envelope_density(c.shared)), sc.dM.data(), sc.dW.data());
    if (pop_.aggregation() || pop_.breakage()) {
      std::fill(sc.dN.begin(), sc.dN.end(), T(0.0));
      kernels::Population::Rates<T> r;
      r.dN = sc.dN.data();
      if (wet_) r.dq[0] = sc.dW.data();
      pop_.rates(*w.pop, population_state(c, sc.N.data(), sc.floor.data(), sc.temp.data()), r);
      for (int i = 0; i < n_; ++i) sc.dM[i] += pm[i] * sc.dN[i];
    }
  }
  // Outlet rates (fraction of a class leaving per second, times the classifier's fraction f_i).
  T exch_rate(0.0);
  if (exchange_.rate) {
    exch_rate = 1.0 / c.par(p_tau_);
    c.res(exchange_.rate) = c.x(exchange_.rate) - exch_rate;
  }
  const T* frac = discharge_fractions(c);
  // What the inlets bring per class, read once: the controller sums it and every class row uses it.
  inlet_flows(c, sc.in_m.data(), sc.in_w.data(), sc.gather);
  if (discharge_ != Discharge::kNone) {
    if (controlled_) {
      const T mass = c.reduce(r_mass_, n_, [&](int i) { return M[i]; });
      const T weighted = frac ? c.reduce(r_tm_, n_, [&](int i) { return frac[i] * M[i]; }) : mass;
      const T fed = c.reduce(r_in_, n_, [&](int i) { return sc.in_m[i]; });
      const T& m_set = c.par(p_mset_);
      const T& tau_c = c.par(p_tauc_);
      const T u = fed + m_sus - exch_rate * mass + (mass - m_set) / tau_c;
      const T eps = kValveSmoothing * m_set / tau_c;
      const T open = softplus(u, eps);
      c.res(discharge_out_.rate) =
          c.x(discharge_out_.rate) - (open - softplus(T(open - c.par(p_rmax_)), eps)) / (weighted + kMassFloor);
    } else {
      c.res(discharge_out_.rate) = c.x(discharge_out_.rate) - c.par(p_k_);
    }
  }
  T surface(0.0), m_water(0.0);
  if (spray_ && wet_) {
    surface = c.reduce(r_surface_, n_, [&](int i) { return M[i] * sc.spm[i]; });
    m_water = c.par(p_spray_) * (1.0 - c.par(p_w_));
  }
  for (int i = 0; i < n_; ++i) {
    const T &in_m = sc.in_m[i], &in_w = sc.in_w[i];
    T out_m(0.0), out_w(0.0);
    for (const Outlet* o : {&exchange_, &discharge_out_}) {
      if (!o->rate) continue;
      const auto [m, wo] = outlet_flow(c, *o, o == &discharge_out_ ? frac : nullptr, i);
      out_m += m, out_w += wo;
    }
    c.res(sM_ + i) = c.xd(sM_ + i) - (sc.dM[i] + in_m - out_m);
    if (wet_) {
      // sprayed water lands in proportion to the class surface; first-order drying towards X_eq
      const T dep = spray_ ? T(m_water * M[i] * sc.spm[i] / (surface + kMassFloor)) : T(0.0);
      const T dry = (W[i] - c.par(p_xeq_) * M[i]) / c.par(p_taudry_);
      c.res(sW_ + i) = c.xd(sW_ + i) - (sc.dW[i] + in_w - out_w + dep - dry);
    }
  }
  c.res(sT_) = c.x(sT_) - c.par(p_t_);
  if (sZero_) c.res(sZero_) = c.x(sZero_);
  return Status::kOk;
}

void ParticleChamber::analytic_jacobian(const Ctx<double>& c, double, JacobianSink& sink) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.sd;
  const double* pm = particle_tables(c, w, sc, pp_, *grid_);
  const double* M = &c.x(sM_);
  const double* W = wet_ ? &c.x(sW_) : nullptr;
  for (int i = 0; i < n_; ++i) sc.N[i] = M[i] / pm[i];
  if (spray_) {
    const double rho = pp_.envelope_density(c.shared);
    const double amount = spray_solids(c) / rho;
    const kernels::GrowthTerms<double> g{1, sc.ones.data(), &amount, true};
    fv_->fluxes(sc.N.data(), g, sc.F.data(), sc.donor.data());
    w.dF.resize(size_t(n_ + 1) * n_);
    fv_->flux_jacobian(sc.N.data(), g, w.dF.data());
    const int m0 = sM_.i, col0 = c.offset + sM_.i;
    // residual rows M_i' - rate: d rate / d M_l = sum_f c_if dF_f/dN_l / m_l, c_if the class's weight of face f
    for (int f = 0; f <= n_; ++f) {
      const double* dF = &w.dF[size_t(f) * n_];
      const int d = sc.donor[f];
      for (int l = 0; l < n_; ++l) {
        if (dF[l] == 0.0) continue;
        const double v = dF[l] / pm[l];
        if (f > 0) sink.add(m0 + f - 1, col0 + l, pm[f - 1] * v);
        if (f < n_)
          sink.add(m0 + f, col0 + l, -pm[f] * v);
        else
          sink.add(m0 + n_ - 1, col0 + l, -rho * grid_->upper_virtual() * v);
      }
      if (!W || d < 0 || f == n_) continue;
      // water flux q = F pi_d, pi_d = W_d / (N_d + floor_d): from class f - 1 (if any) to class f
      const double den = sc.N[d] + sc.floor[d], pi = W[d] / den;
      auto water = [&](int col, double v) {
        if (f > 0) sink.add(sW_.i + f - 1, col, v);
        sink.add(sW_.i + f, col, -v);
      };
      for (int l = 0; l < n_; ++l) {
        double v = dF[l] * pi;
        if (l == d) v -= sc.F[f] * pi / den;
        if (v != 0.0) water(col0 + l, v / pm[l]);
      }
      water(c.offset + sW_.i + d, sc.F[f] / den);
    }
  }
  if (pop_.aggregation() || pop_.breakage()) {
    if (!w.mapped) {
      kernels::Population::Map& m = w.map;
      m = {};
      for (int i = 0; i < n_; ++i) {
        m.N_col.push_back(c.offset + sM_.i + i), m.N_scale.push_back(1.0 / w.pm[i]);
        m.N_row.push_back(sM_.i + i), m.N_factor.push_back(-w.pm[i]);
        m.field_col[static_cast<int>(Field::kTemperature)].push_back(c.offset + sT_.i);
      }
      if (wet_) {
        m.q_col.assign(1, {}), m.q_row.assign(1, {});
        for (int i = 0; i < n_; ++i) m.q_col[0].push_back(c.offset + sW_.i + i), m.q_row[0].push_back(sW_.i + i);
      }
      w.mapped = true;
    }
    pop_.jacobian(*w.pop, population_state(c, sc.N.data(), sc.floor.data(), sc.temp.data()), w.map, sink);
  }
}

template <class T>
void ParticleChamber::init(InitCtx<T>& c) const {
  // Log-normal mass distribution over the cells, tails beyond the grid in the end classes; in T, so that initial
  // sensitivities to d50_0 and sigma_0 are exact.
  const auto& de = grid_->diameter_edges();
  auto cdf = [&](int e) {
    using std::erfc, std::log;
    return T(0.5 * erfc(-log(de[e] / c.par(p_d50_)) / (log(c.par(p_sigma_)) * std::sqrt(2.0))));
  };
  T below(0.0);
  for (int i = 0; i < n_; ++i) {
    const T upto = i == n_ - 1 ? T(1.0) : cdf(i + 1);
    c.x(sM_ + i) = c.par(p_mass_) * (upto - below);
    below = upto;
    if (wet_) c.x(sW_ + i) = c.x(sM_ + i) * c.par(p_x0_);
  }
  c.x(sT_) = c.par(p_t_);
  if (sZero_) c.x(sZero_) = T(0.0);
  if (exchange_.rate) c.x(exchange_.rate) = 1.0 / c.par(p_tau_);
  if (discharge_out_.rate) c.x(discharge_out_.rate) = controlled_ ? T(0.0) : T(c.par(p_k_));
}

template <class T>
void ParticleChamber::outputs(const Ctx<T>& c) const {
  Work& w = c.template ws<Work>();
  auto& sc = w.template scratch<T>();
  const T* pm = particle_tables(c, w, sc, pp_, *grid_);
  const T* M = &c.x(sM_);
  const auto& dp = grid_->diameter_pivots();
  T mass(0.0), water(0.0), mu[4] = {T(0.0), T(0.0), T(0.0), T(0.0)};
  for (int i = 0; i < n_; ++i) {
    mass += M[i];
    if (wet_) water += c.x(sW_ + i);
    const T N = M[i] / pm[i];
    T dk(1.0);
    for (int k = 0; k < 4; ++k) mu[k] += N * dk, dk *= dp[i];
  }
  c.out(o_mass_) = mass;
  if (wet_) c.out(o_moisture_) = water / (mass + kMassFloor);
  const double q[3] = {0.1, 0.5, 0.9};
  T dq[3] = {T(0.0), T(0.0), T(0.0)};
  if (mass > 0.0) kernels::characteristic_diameters_of_mass(grid_->diameter_edges(), M, q, 3, dq);
  for (int k = 0; k < 3; ++k) c.out(o_d_[k]) = dq[k];
  const bool any = mu[0] > 0.0;
  c.out(o_d32_) = any ? T(mu[3] / mu[2]) : T(0.0);
  const T mean = any ? T(mu[1] / mu[0]) : T(0.0);
  c.out(o_dmean_) = mean;
  using std::sqrt;
  const T var = any ? T(mu[2] / mu[0] - mean * mean) : T(0.0);
  c.out(o_sigma_) = var > 0.0 ? T(sqrt(var)) : T(0.0);
  if (spray_)  // Eq. (7.33), paper 003, with mu_2 of the class pivots
    c.out(o_g_) = any ? T(2.0 * spray_solids(c) / (pp_.envelope_density(c.shared) * kernels::kPi * mu[2])) : T(0.0);
  c.out(o_particles_) = mu[0];
  auto outflow = [&](const Outlet& o, const T* frac) {
    T m(0.0);
    for (int i = 0; i < n_; ++i) m += outlet_flow(c, o, frac, i).first;
    return m;
  };
  if (discharge_out_.rate) c.out(o_dis_) = outflow(discharge_out_, discharge_fractions(c));
  if (exchange_.rate) c.out(o_exch_) = outflow(exchange_, static_cast<const T*>(nullptr));
  c.out(o_top_) = mass > 0.0 ? T(M[n_ - 1] / mass) : T(0.0);
  c.out(o_hold_solids_) = mass;
  c.out(o_hold_water_) = water;
  c.out(o_hold_energy_) = (mass * c.sh(pp_.cp_s) + water * c.par(p_cpl_)) * (c.x(sT_) - props::kT0);
  const Boundary<T> b = boundary(c);
  c.out(o_heat_) = b.energy_in - b.h_spray;
  c.out(o_vapour_) = b.vapour;
  for (int i = 0; i < n_; ++i) {
    c.out(o_psd_d_ + i) = T(dp[i]);
    c.out(o_psd_m_ + i) = M[i];
  }
}

// Balance terms that cross the flowsheet's boundary here: the spray's solids, water and enthalpy, the vapour and its
// enthalpy, and the heat the gas supplies to hold the bed at T_bed, which is what closes the energy balance of the
// hold-up: Q = dH/dt - (enthalpy in with the inlets) + (enthalpy out with the outlets) - H_spray + H_vapour.
template <class T>
ParticleChamber::Boundary<T> ParticleChamber::boundary(const Ctx<T>& c) const {
  const T cp_s = c.sh(pp_.cp_s), cp_l = c.par(p_cpl_);
  const T& t = c.x(sT_);
  T vapour(0.0), h_in(0.0), h_out(0.0), dh(0.0), capacity(0.0);
  const T* frac = discharge_fractions(c);
  for (int i = 0; i < n_; ++i) {
    const T wi = wet_ ? c.x(sW_ + i) : T(0.0);
    capacity += c.x(sM_ + i) * cp_s + wi * cp_l;
    dh += (c.xd(sM_ + i) * cp_s + (wet_ ? c.xd(sW_ + i) : T(0.0)) * cp_l) * (t - props::kT0);
    if (wet_) vapour += (wi - c.par(p_xeq_) * c.x(sM_ + i)) / c.par(p_taudry_);
    for (PortId p : inlets_) {
      const T& wf = c.port(p, solids::water(n_, i));
      h_in += (c.port(p, solids::mdot(i)) * cp_s + wf * cp_l) * (c.port(p, solids::T(n_)) - props::kT0);
      if (!wet_) vapour += wf;  // fed water evaporates at once
    }
    for (const Outlet* o : {&exchange_, &discharge_out_}) {
      if (!o->rate) continue;
      const auto [m, wo] = outlet_flow(c, *o, o == &discharge_out_ ? frac : nullptr, i);
      h_out += (m * cp_s + wo * cp_l) * (t - props::kT0);
    }
  }
  dh += capacity * c.xd(sT_);
  Boundary<T> b;
  b.h_spray = b.water_in = T(0.0);
  if (spray_) {
    b.water_in = c.par(p_spray_) * (1.0 - c.par(p_w_));
    if (!wet_) vapour += b.water_in;
    b.h_spray = c.par(p_spray_) * cp_l * (c.par(p_tspray_) - props::kT0);
  }
  b.vapour = vapour;
  b.h_vapour = vapour * props::vapour_enthalpy(t);
  b.energy_in = dh - h_in + h_out + b.h_vapour;  // = Q + H_spray
  return b;
}

template <class T>
void ParticleChamber::quad(const Ctx<T>& c) const {
  const Boundary<T> b = boundary(c);
  if (spray_) {
    c.r[q_solids_in_.i] = spray_solids(c);
    c.r[q_water_in_.i] = b.water_in;
  }
  c.r[q_water_out_.i] = b.vapour;
  c.r[q_energy_in_.i] = b.energy_in;
  c.r[q_energy_out_.i] = b.h_vapour;
}

template Status ParticleChamber::eval(const Ctx<double>&) const;
template Status ParticleChamber::eval(const Ctx<Jet>&) const;
template void ParticleChamber::init(InitCtx<double>&) const;
template void ParticleChamber::init(InitCtx<Jet>&) const;
template void ParticleChamber::outputs(const Ctx<double>&) const;
template void ParticleChamber::outputs(const Ctx<Jet>&) const;
template void ParticleChamber::quad(const Ctx<double>&) const;
template void ParticleChamber::quad(const Ctx<Jet>&) const;

}  // namespace granuflow::units
