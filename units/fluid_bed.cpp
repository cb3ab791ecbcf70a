#include "fluid_bed.hpp"

#include <cmath>
#include <iterator>
#include <tuple>
#include <type_traits>
#include <vector>

#include "bed_layering.hpp"
#include "chamber_outlet.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "granuflow/renamed.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/discretization/psd_setting.hpp"
#include "kernels/drying/drying_closures.hpp"
#include "kernels/drying/paper001_drying.hpp"
#include "kernels/limited.hpp"
#include "kernels/particle_geometry.hpp"
#include "kernels/population/population.hpp"
#include "kernels/simd_math.hpp"
#include "kernels/transfer/fluid_bed_transfer.hpp"
#include "kernels/wetting/spray_deposition.hpp"
#include "kernels/wetting/stokes_report.hpp"
#include "paper001_streams.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

namespace p1 = kernels::paper001;
namespace def = kernels::paper001::defaults;
namespace tr = kernels::transfer;
namespace holdup = paper001::holdup;
namespace wetting = paper001::wetting;
using kernels::Field;

struct Work : Workspace {
  kernels::Population::WorkPtr pop;
  std::vector<double> pm, spm;  // particle mass and surface per mass of each class at the run's parameters
  template <class T>
  struct Scratch {
    std::vector<T> pm, spm, N, floor, dN, dW, dry, q, fwet, xwet, temp, nu, area, flux, lay_m, lay_w, shape;
    BedLayering::Scratch<T> lay;
    void resize(int n) {
      for (auto* v :
           {&pm, &spm, &N, &floor, &dN, &dW, &dry, &q, &fwet, &xwet, &temp, &nu, &area, &flux, &lay_m, &lay_w})
        v->assign(n, T(0.0));
      shape.assign(n + 1, T(0.0));
    }
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  kernels::Population::Map map;  // the engine's inputs and rates in the unit's Jacobian (built on first use)
  bool mapped = false;
};

class FluidBed : public UnitBase<FluidBed> {
 public:
  std::string type() const override { return "fluid_bed"; }

  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st);
    require_water(ps, st, "the paper-001 bed dries per-class water");
    pp_ = ps.params();
    grid_ = ps.grid();
    n_ = grid_->size();
    const std::string t6 = "paper 001, Table 6", t8 = "paper 001, Table 8", dec = "docs/paper001_decisions.md";
    p_mass_ = s.add_param({"bed_mass", "kg", 15.0, 1e-3, 1e4, "initial wet bed mass", "paper 001, section 3.1.3"});
    p_x0_ = s.add_param({"X0", "kg/kg", 0.03 / 0.97, 0.0, 1.0, "initial moisture, dry basis", dec});
    psd_ = kernels::declare_table_psd(st, *grid_, "initial_", "initial bed");
    if (!psd_.table) {
      p_d50_ =
          s.add_param({"d50_0", "m", 200e-6, 1e-6, 1e-2, "initial mass median diameter (log-normal in mass)", dec});
      p_sigma_ = s.add_param({"sigma_0", "-", 1.5, 1.01, 5.0, "initial geometric standard deviation", dec});
    }
    p_t0_ = s.add_param({"T0", "K", 333.15, 250.0, 500.0, "initial solids temperature", dec});
    p_cpl_ = s.add_param({"cp_l", "J/(kg K)", def::kLiquidCp, 100.0, 1e4, "liquid heat capacity", t6});
    p_abed_ = s.add_param({"A_bed", "m2", def::kBedArea, 1e-4, 100.0, "bed cross-section (A_inlet)", t6});
    p_xcr_ =
        s.add_param({"X_cr", "kg/kg", def::kCriticalMoisture, 1e-4, 1.0, "critical moisture content, Eq. (80)", t8});
    p_sh_ = s.add_param(
        {"sh_corr", "-", def::kBulkSherwoodCorrection, 1e-3, 100.0, "bulk Sherwood correction, Eq. (74)", t8});
    p_betmm_ = s.add_param({"bet_mm", "kg/kg", def::kBetMonolayer, 0.0, 1.0, "BET monolayer moisture, Eq. (81)", t8});
    p_betn_ = s.add_param({"bet_n", "-", def::kBetN, 1.0, 100.0, "BET n, Eq. (81)", t8});
    p_dv_ = s.add_param({"D_v", "m2/s", def::kVapourDiffusivity, 1e-7, 1e-3, "vapour diffusivity", t6});
    p_lambda_ = s.add_param({"lambda_g", "W/(m K)", def::kGasConductivity, 1e-3, 1.0, "gas thermal conductivity", t6});
    closures_.declare(s, st, "linear", true);  // paper 000, sections 5.2, 5.4.1 (default: paper 001's Eq. (79), film)
    deposition_.declare(s, st), stokes_.declare(s, st);  // paper 000, sections 5.1.4, 5.5, 5.6 (default: neither)
    declare_population(s, st);
    declare_binder(st);
    const bool discharge = declare_states(s, st);
    declare_ports(s, discharge);
    declare_structure(s);
    declare_outputs(s);
  }

 private:
  void declare_population(UnitSpec& s, Settings& st) {
    // Aggregation, breakage (and growth) by the population engine, each kernel's parameters and settings under the
    // names they carry in every unit (agg_ln_beta0, sel_k_break, agg_beta0_basis, sel_size_unit ...; the bare and
    // breakage_ names of earlier versions are deprecated aliases).
    // Paper 001: glass-transition kernel on the fixed pivot, Vogel-Peukert breakage with tanh power-law fragments,
    // aggregates beyond the grid kept in the top class (fold).
    kernels::PopulationOptions o;
    o.aggregation = "glass_transition", o.aggregation_scheme = "fixed_pivot";
    o.breakage = "vogel_peukert", o.fragments = "tanh_power_law", o.breakage_scheme = "fixed_pivot";
    o.outside = kernels::Outside::kFold;
    for (const char* family : {"agg_", "frag_", "growth_"}) st.rename_prefix(family, "");
    st.rename_prefix("sel_", "breakage_");
    o.properties = {"water"};
    const size_t first = s.params().size();
    pop_.declare(s, st, grid_, o);
    for (size_t k = first; k < s.params().size(); ++k)
      add_renamed_param(type(), s.params()[k].name.substr(s.params()[k].name.find('_') + 1), s.params()[k].name);
    for (Field f : {Field::kMoisture, Field::kLiquidFraction})
      if (pop_.needs().field(f))
        throw ConfigError(st.where() +
                          ": the fluid bed supplies its kernels the wetted fraction, spot moisture and "
                          "temperature, not the " +
                          std::string(kernels::field_name(f)));
    if (pop_.needs().number)
      throw ConfigError(st.where() + ": kernels that read particle numbers are not supported in the fluid bed");
  }

  // Solids dissolved in the spray (spray_nozzle.w) deposit with the droplets and stay as a layer when the water dries
  // (docs/binder_granulation.md). The binder solid is read as the bed's own solid (maltodextrin in paper 001): the
  // layer takes the particles' density and heat capacity and the wet spot's glass transition is Gordon-Taylor of water
  // and that one solid (Eq. (54)). Another binder material would be a second solid component: refused by name.
  void declare_binder(Settings& st) {
    const std::string b = st.get_choice("binder", "bed_solid", {},
                                        "material of the solids dissolved in the spray: bed_solid (the binder is the "
                                        "bed's own solid, e.g. maltodextrin on maltodextrin); no other is modelled");
    if (b != "bed_solid")
      throw ConfigError(st.where() + ".binder = '" + b +
                        "': a binder other than the bed solid is not modelled yet (its layer would be a second "
                        "solid component with its own density and glass transition); allowed: bed_solid");
    layering_.declare(st, *grid_);
  }

  // The states; with a discharge also its parameter and rate state. Returns whether the bed discharges.
  bool declare_states(UnitSpec& s, Settings& st) {
    // Tolerance scales of the class inventories are those of the whole bed (about 10 kg solids, 0.5 kg water):
    // an emptied class needs no more absolute accuracy than the bed it belongs to.
    sM_ = s.add_states("M", n_, StateKind::Differential, "kg", 10.0);
    sW_ = s.add_states("W", n_, StateKind::Differential, "kg", 0.5);
    s.set_nonnegative(sM_, n_), s.set_nonnegative(sW_, n_);
    sH_ = s.add_state("H", StateKind::Differential, "J", 1e6);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    sU0_ = s.add_state("u0", StateKind::Algebraic, "m/s", 1.0);
    sVap_ = s.add_state("m_vap", StateKind::Algebraic, "kg/s", 1e-3);
    sQ_ = s.add_state("Q", StateKind::Algebraic, "W", 1e3);
    // Continuous operation: an optional solids feed, and a discharge of a fixed fraction of the hold-up per second
    // (well mixed: every class alike) when the setting asks for one. A batch bed has neither and pays nothing.
    const bool discharge = st.get_choice("discharge", "none", {"none", "unclassified"},
                                         "solids leaving the bed: none (batch) or a fraction of the well-mixed "
                                         "hold-up per second (continuous operation)") == "unclassified";
    if (discharge) {
      p_kdis_ = s.add_param({"k_discharge", "1/s", 1e-3, 0.0, 10.0,
                             "discharge rate: fraction of the hold-up leaving per second", "operating input"});
      sRate_ = s.add_state("discharge_rate", StateKind::Algebraic, "1/s", 1e-3);
    }
    return discharge;
  }

  void declare_ports(UnitSpec& s, bool discharge) {
    const std::vector<double>& d = grid_->diameter_pivots();
    wet_ = s.add_port("wetting", paper001::wetting_stream(), PortDir::In, n_, true);
    s.set_port_grid(wet_, d);
    gas_ = s.add_port("gas", streams::gas(), PortDir::In);
    inlet_ = s.add_port("inlet", streams::gas(), PortDir::In);
    const PortId vap = s.add_port("vapour", streams::vapour(), PortDir::Out, 0, true);
    s.provide(vap, vapour::kMdot, sVap_);
    s.provide(vap, vapour::kT, sT_);
    s.provide(s.add_port("heat", streams::heat(), PortDir::In, 0, true), heat::kQ, sQ_);
    feed_ = s.add_port("feed", streams::solids(), PortDir::In, n_, true);
    s.set_port_grid(feed_, d);
    if (discharge) {  // the flows k M_i, k W_i: computed inline by the companion "<bed>:discharge"
      const PortId hold = s.add_port("discharge_holdup", chamber_holdup(), PortDir::Out, n_);
      s.set_port_grid(hold, d);
      for (int i = 0; i < n_; ++i) {
        s.provide(hold, holdup_fields::mass(i), sM_ + i);
        s.provide(hold, holdup_fields::water(n_, i), sW_ + i);
      }
      s.provide(hold, holdup_fields::T(n_), sT_);
      s.provide(hold, holdup_fields::rate(n_), sRate_);
      const ChamberOutletSpec spec{n_, true, nullptr, d};
      s.add_companion({"discharge", [spec](const std::string& owner) { return make_chamber_outlet(owner, spec); }, hold,
                       "discharge"});
    }
    const PortId probe = s.add_port("state", paper001::holdup_stream(), PortDir::Probe, n_);
    s.set_port_grid(probe, d);
    for (int i = 0; i < n_; ++i) {
      s.provide(probe, holdup::mass(i), sM_ + i);
      s.provide(probe, holdup::water(n_, i), sW_ + i);
    }
    s.provide(probe, holdup::T(n_), sT_);
    s.provide(probe, holdup::u0(n_), sU0_);
  }

  void declare_structure(UnitSpec& s) {
    // Class structure for the Jacobian: class rows and columns M_i, W_i and the spray zone's per-class fields; the
    // bed-wide quantities read the classes through sums.
    ClassLayout layout{n_,
                       {sM_, sW_},
                       {{wet_, wetting::mdot(0)},
                        {wet_, wetting::fwet(n_, 0)},
                        {wet_, wetting::Xwet(n_, 0)},
                        {feed_, solids::mdot(0)},
                        {feed_, solids::water(n_, 0)}}};
    layout.class_local_newton = pop_.aggregation() || pop_.breakage();  // drying and heat act per class
    s.set_classes(layout);
    r_surface_ = s.add_reduction("particle surface");
    r_drying_ = s.add_reduction("drying");
    r_heat_ = s.add_reduction("gas-solid heat flow");
    r_deposit_ = s.add_reduction("deposited liquid");
    r_capacity_ = s.add_reduction("heat capacity");
    r_feed_ = s.add_reduction("solids fed");
    r_feed_water_ = s.add_reduction("water fed");
    deposition_.declare_reductions(s);
    s.set_analytic_part();  // the population balance's terms (engine)
  }

  void declare_outputs(UnitSpec& s) {
    for (const char* o : {"d10", "d50", "d90", "d5", "d16", "d25", "d75", "d84", "d95"})
      o_quantiles_.push_back(s.add_output(o, "m"));
    o_moisture_ = s.add_output("moisture", "kg/kg");
    o_moisture_wet_ = s.add_output("moisture_wet", "kg/kg");
    o_particles_ = s.add_output("particles", "-");
    o_top_ = s.add_output("top_class_fraction", "-", OutputRole::kGridEnd);
    o_reg_eta_ = s.add_output("reg_eta", "-", OutputRole::kRegularization);
    o_reg_a_ = s.add_output("reg_activity_cap", "-", OutputRole::kRegularization);  // a < 0.99, p_sat < 0.9 p
    o_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
    o_solids_ = s.add_output("balance_solids_hold", "kg", OutputRole::kBalanceHold, "solids");
    o_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
    std::tie(o_psd_d_, o_psd_m_) = s.add_size_distribution(n_, grid_->diameter_edges());
    if (psd_.table) o_outside_ = s.add_output("initial_psd_outside", "-");  // measured mass folded into end classes
  }

 public:
  std::unique_ptr<Workspace> workspace() const override {
    auto w = std::make_unique<Work>();
    w->pop = pop_.make_work();
    w->sd.resize(n_);
    w->sj.resize(n_);
    return w;
  }

  void configure(const UnitSpec&, const double* p, const double* shared, Workspace& ws) const override {
    Work& w = static_cast<Work&>(ws);
    w.pm.resize(n_), w.spm.resize(n_);
    particle_tables(shared, w.pm.data(), w.spm.data());
    pop_.configure(*w.pop, p, "unit fluid_bed");
    w.mapped = false;
  }
  void check(const UnitSpec&, const double* p) const override { closures_.check(p, "drying_curve"); }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    Work& w = c.template ws<Work>();
    auto& sc = w.template scratch<T>();
    const T* pm = tables(c, sc);
    const T* M = &c.x(sM_);
    const T* W = &c.x(sW_);
    const T& t_s = c.x(sT_);
    const bool wet = c.connected(wet_);
    // Eqs. (20)-(26): aggregation and breakage move solids and water (the engine; its Jacobian is analytic).
    std::fill(sc.dN.begin(), sc.dN.end(), T(0.0));
    std::fill(sc.dW.begin(), sc.dW.end(), T(0.0));
    if (!c.in_jacobian() && (pop_.aggregation() || pop_.breakage())) {
      kernels::Population::State<T> st = population_state(c, sc, pm);
      kernels::Population::Rates<T> r;
      r.dN = sc.dN.data();
      r.dq[0] = sc.dW.data();
      pop_.rates(*w.pop, st, r);
    }
    // Eqs. (70)-(89): drying and heat transfer per class; the bed's particle surface enters Eqs. (74), (87).
    const T surface = c.reduce(r_surface_, n_, [&](int i) { return M[i] * sc.spm[i]; });
    const GasSide<T> g = gas_side(c, t_s, tr::bed_area_ratio(surface, c.par(p_abed_)));
    const TransferParams<T> tp = transfer_params(c);
    const double* d = grid_->diameter_pivots().data();
    T *dry = sc.dry.data(), *q = sc.q.data(), *nu = sc.nu.data(), *area = sc.area.data(), *flux = sc.flux.data();
    // In doubles vector loops (libmvec's log1p, kernels/simd_math.hpp). The drying rate, Eqs. (70), (79), is formed
    // in a loop of its own: beside the clamp of the drying curve, GCC's partial-redundancy elimination moves the
    // product into the clamp's three cases, which if-conversion cannot flatten, and the class loop stayed scalar.
    const int n = n_;  // a local bound: stores through the arrays could change the member n_
#pragma omp simd
    for (int i = 0; i < n; ++i) class_transfer(tp, d[i], M[i], W[i], pm[i], g, &nu[i], &area[i], &flux[i], &q[i]);
    closures_.curve(c.p, n, nu), closures_.surface(c.p, W, n, area);  // the chosen closures (heat keeps the area)
#pragma omp simd
    for (int i = 0; i < n; ++i) dry[i] = p1::drying_rate(nu[i], area[i], flux[i]);
    const T m_vap = c.reduce(r_drying_, n_, [&](int i) { return sc.dry[i]; });
    const T q_sum = c.reduce(r_heat_, n_, [&](int i) { return sc.q[i]; });
    const T dep = c.reduce(r_deposit_, n_, [&](int i) { return deposit(c, i, wet); });
    const T cp_s = c.sh(pp_.cp_s);
    const T capacity = c.reduce(r_capacity_, n_, [&](int i) { return M[i] * cp_s + W[i] * c.par(p_cpl_); });
    const bool fed = c.connected(feed_);
    const T m_fed = c.reduce(r_feed_, n_, [&](int i) { return fed ? c.port(feed_, solids::mdot(i)) : T(0.0); });
    const T w_fed =
        c.reduce(r_feed_water_, n_, [&](int i) { return fed ? c.port(feed_, solids::water(n_, i)) : T(0.0); });
    const T k_out = sRate_ ? c.x(sRate_) : T(0.0);
    if (sRate_) c.res(sRate_) = c.x(sRate_) - c.par(p_kdis_);
    // The deposit's dissolved solids (a fraction w of it) layer the particles; its water wets them. Nothing to
    // layer (a water spray) skips the layering, so that it changes no bit of a result.
    const T w_dep = wet ? c.port(wet_, wetting::w(n_)) : T(0.0);
    const bool layering = !c.in_jacobian() && wet && !carries_nothing(T(w_dep * dep));  // in the Jacobian: analytic
    if (layering) layering_rates(c, sc, pm, T(w_dep * dep));
    const bool filter = deposition_.active();  // the share of the deposit the particles filter; the rest evaporates
    const T kept = filter ? deposition_.filtered_share(c, g.u0, g.t_g, c.port(gas_, gas::kP), g.y, M, d, n_) : T(1.0);
    for (int i = 0; i < n_; ++i) {
      T in_m(0.0), in_w(0.0), out_m(0.0), out_w(0.0);
      if (fed) in_m = c.port(feed_, solids::mdot(i)), in_w = c.port(feed_, solids::water(n_, i));
      if (sRate_) out_m = k_out * M[i], out_w = k_out * W[i];  // a well-mixed outlet: every class alike
      T rate_m = pm[i] * sc.dN[i] + in_m - out_m;              // Eq. (20), paper 001, in mass
      const T dep_i = filter ? T(kept * deposit(c, i, wet)) : deposit(c, i, wet);
      T rate_w = dep_i * (1.0 - w_dep) - sc.dry[i] + sc.dW[i] + in_w - out_w;  // Eq. (58)
      if (layering) rate_m += sc.lay_m[i], rate_w += sc.lay_w[i];
      c.res(sM_ + i) = c.xd(sM_ + i) - rate_m;
      c.res(sW_ + i) = c.xd(sW_ + i) - rate_w;
    }
    const T t_liq = wet ? c.port(wet_, wetting::T(n_)) : T(props::kT0);
    // Eq. (59), paper 001, conservative: deposited liquid at its enthalpy (dissolved solids included, at the liquid
    // heat capacity like spray_nozzle's balance_energy_in), drying vapour leaves at h_v(T_S)
    // (the particle supplies the latent heat), gas-solid heat transfer Q; fed solids bring their enthalpy, the
    // discharge takes its share of the bed's.
    T h_flow(0.0);
    if (fed) h_flow += (m_fed * cp_s + w_fed * c.par(p_cpl_)) * (c.port(feed_, solids::T(n_)) - props::kT0);
    if (sRate_) h_flow -= k_out * c.x(sH_);
    c.res(sH_) = c.xd(sH_) - (dep * props::liquid_water_enthalpy(t_liq, c.par(p_cpl_)) -
                              c.x(sVap_) * props::vapour_enthalpy(t_s) + c.x(sQ_) + h_flow);
    c.res(sT_) = c.x(sH_) - capacity * (t_s - props::kT0);  // Eq. (60), paper 001
    c.res(sU0_) = c.x(sU0_) - inlet_velocity(c);
    c.res(sVap_) = c.x(sVap_) - (filter ? T(m_vap + (1.0 - kept) * dep * (1.0 - w_dep)) : m_vap);
    c.res(sQ_) = c.x(sQ_) - q_sum;
    return Status::kOk;
  }

  void analytic_jacobian(const Ctx<double>& c, double, JacobianSink& sink) const override {
    Work& w = c.template ws<Work>();
    layering_jacobian(c, w, sink);
    if (!pop_.aggregation() && !pop_.breakage()) return;
    if (!w.mapped) {
      kernels::Population::Map& m = w.map;
      const auto& ports = *c.port_index;
      m = {};
      for (int i = 0; i < n_; ++i) {
        m.N_col.push_back(c.offset + sM_.i + i), m.N_scale.push_back(1.0 / w.pm[i]);
        m.N_row.push_back(sM_.i + i), m.N_factor.push_back(-w.pm[i]);
      }
      m.q_col.assign(1, {}), m.q_row.assign(1, {});
      for (int i = 0; i < n_; ++i) m.q_col[0].push_back(c.offset + sW_.i + i), m.q_row[0].push_back(sW_.i + i);
      auto field = [&](Field f) -> std::vector<int>& { return m.field_col[static_cast<int>(f)]; };
      for (int i = 0; i < n_; ++i) {
        field(Field::kWettedFraction).push_back(ports[wet_.i][wetting::fwet(n_, i)]);
        field(Field::kSpotMoisture).push_back(ports[wet_.i][wetting::Xwet(n_, i)]);
        field(Field::kTemperature).push_back(c.offset + sT_.i);
      }
      w.mapped = true;
    }
    kernels::Population::State<double> st = population_state(c, w.sd, w.pm.data());
    pop_.jacobian(*w.pop, st, w.map, sink);
  }

  template <class T>
  void init(InitCtx<T>& c) const {
    const T dry = c.par(p_mass_) / (1.0 + c.par(p_x0_));
    // Initial log-normal mass distribution over the cells, tails beyond the grid folded into the end classes;
    // in T, so that initial sensitivities to d50_0 and sigma_0 are exact. Or a measured table's (mapped in declare).
    const auto& de = grid_->diameter_edges();
    auto cdf = [&](int e) {
      using std::erfc, std::log;
      return T(0.5 * erfc(-log(de[e] / c.par(p_d50_)) / (log(c.par(p_sigma_)) * std::sqrt(2.0))));
    };
    T capacity(0.0), below(0.0);
    for (int i = 0; i < n_; ++i) {
      const T upto = psd_.table ? T(0.0) : i == n_ - 1 ? T(1.0) : cdf(i + 1);
      c.x(sM_ + i) = psd_.table ? dry * psd_.psd.mass[i] : dry * (upto - below);
      below = upto;
      c.x(sW_ + i) = c.x(sM_ + i) * c.par(p_x0_);
      capacity += c.x(sM_ + i) * c.sh(pp_.cp_s) + c.x(sW_ + i) * c.par(p_cpl_);
    }
    c.x(sT_) = c.par(p_t0_);
    c.x(sH_) = capacity * (c.par(p_t0_) - props::kT0);
    c.x(sU0_) = T(0.5);
    c.x(sVap_) = T(0.0);
    c.x(sQ_) = T(0.0);
    if (sRate_) c.x(sRate_) = c.par(p_kdis_);
  }

  template <class T>
  void outputs(const Ctx<T>& c) const {
    Work& w = c.template ws<Work>();
    auto& sc = w.template scratch<T>();
    const T* pm = tables(c, sc);
    const T* M = &c.x(sM_);
    const T* W = &c.x(sW_);
    T m(0.0), water(0.0), number(0.0);
    for (int i = 0; i < n_; ++i) m += M[i], water += W[i], number += M[i] / pm[i];
    const double q[] = {0.1, 0.5, 0.9, 0.05, 0.16, 0.25, 0.75, 0.84, 0.95};  // order of o_quantiles_
    T dq[std::size(q)];
    kernels::characteristic_diameters_of_mass(grid_->diameter_edges(), M, q, static_cast<int>(o_quantiles_.size()), dq);
    for (size_t k = 0; k < o_quantiles_.size(); ++k) c.out(o_quantiles_[k]) = dq[k];
    stokes_.outputs(c, dq[1], T(pp_.envelope_density(c.shared)));  // paper 000, section 5.6
    c.out(o_moisture_) = water / m;
    c.out(o_moisture_wet_) = water / (m + water);
    c.out(o_particles_) = number;
    c.out(o_top_) = M[n_ - 1] / m;
    T surface(0.0);
    for (int i = 0; i < n_; ++i) surface += M[i] * sc.spm[i];
    const GasSide<T> g = gas_side(c, c.x(sT_), tr::bed_area_ratio(surface, c.par(p_abed_)));
    deposition_.outputs(c, g.u0, g.t_g, c.port(gas_, gas::kP), g.y, M, grid_->diameter_pivots().data(), n_);
    int reg_eta = 0;  // the classes whose Eq. (80) class_transfer() regularizes, without its transfer coefficients
    for (int i = 0; i < n_; ++i)
      reg_eta += p1::normalized_moisture(T(W[i] / (M[i] + kMassFloor)), g.x_eq, c.par(p_xcr_)).active;
    c.out(o_reg_eta_) = T(reg_eta);
    c.out(o_reg_a_) = T(g.activity_capped + g.saturation_capped);
    c.out(o_water_) = water;
    c.out(o_solids_) = m;
    c.out(o_energy_) = c.x(sH_);
    for (int i = 0; i < n_; ++i) {
      c.out(o_psd_d_ + i) = T(grid_->diameter_pivots()[i]);
      c.out(o_psd_m_ + i) = M[i];
    }
    if (o_outside_) c.out(o_outside_) = T(psd_.psd.outside());
  }

 private:
  // Particle mass and surface per mass of each class (the envelope density relates size and mass).
  template <class T>
  void particle_tables(const T* shared, T* pm, T* spm) const {
    const T rho = pp_.envelope_density(shared);
    for (int i = 0; i < n_; ++i) {
      pm[i] = rho * grid_->pivot(i);
      spm[i] = kernels::sphere_surface(grid_->diameter_pivots()[i]) / pm[i];
    }
  }
  // The tables for this evaluation: cached for doubles; Jets recompute them, so that sensitivities to the product
  // properties (rho_s, eps_intra) carry through. Returns the particle masses; sc.spm holds the surfaces per mass.
  template <class T>
  const T* tables(const Ctx<T>& c, typename Work::template Scratch<T>& sc) const {
    if constexpr (std::is_same_v<T, double>) {
      const Work& w = c.template ws<Work>();
      std::copy(w.spm.begin(), w.spm.end(), sc.spm.begin());
      return w.pm.data();
    } else {
      particle_tables(c.shared, sc.pm.data(), sc.spm.data());
      return sc.pm.data();
    }
  }

  // The binder's layering (bed_layering.hpp) in sc.lay_m, sc.lay_w, with the growth shape Eq. (29)'s tau at the faces.
  template <class T>
  void layering_rates(const Ctx<T>& c, typename Work::template Scratch<T>& sc, const T* pm, const T& m_s) const {
    std::fill(sc.lay_m.begin(), sc.lay_m.end(), T(0.0));
    std::fill(sc.lay_w.begin(), sc.lay_w.end(), T(0.0));
    layering_.rates(layer_classes(c, sc, pm), m_s, sc.lay, sc.lay_m.data(), sc.lay_w.data());
  }
  template <class T>
  BedLayering::Classes<T> layer_classes(const Ctx<T>& c, typename Work::template Scratch<T>& sc, const T* pm) const {
    for (int i = 0; i < n_; ++i) sc.N[i] = c.x(sM_ + i) / pm[i], sc.floor[i] = kMassFloor / pm[i];
    for (int f = 0; f <= n_; ++f) sc.shape[f] = c.port(wet_, wetting::tau_face(n_, f));
    return {sc.N.data(), &c.x(sW_), sc.floor.data(), pm, sc.shape.data(), pp_.envelope_density(c.shared)};
  }
  void layering_jacobian(const Ctx<double>& c, Work& w, JacobianSink& sink) const {
    if (!c.connected(wet_)) return;
    const auto& cols = (*c.port_index)[wet_.i];
    const double w_dep = c.port(wet_, wetting::w(n_));
    double dep = 0.0;
    for (int i = 0; i < n_; ++i) dep += c.port(wet_, wetting::mdot(i));
    BedLayering::Columns jc{sM_.i, sW_.i, c.offset + sM_.i, c.offset + sW_.i, {}, {{cols[wetting::w(n_)], dep}}};
    for (int i = 0; i < n_; ++i) jc.amount_cols.push_back({cols[wetting::mdot(i)], w_dep});
    for (int f = 0; f <= n_; ++f) jc.shape_cols.push_back(cols[wetting::tau_face(n_, f)]);
    layering_.jacobian(layer_classes(c, w.sd, w.pm.data()), w_dep * dep, w.sd.lay, jc, sink);
  }

  template <class T>
  T deposit(const Ctx<T>& c, int i, bool wet) const {
    return wet ? c.port(wet_, wetting::mdot(i)) : T(0.0);
  }

  // The engine's inputs: class numbers, water per class, and the fields its kernels read (wetted fraction and
  // wet-spot moisture from the spray zone, the bed temperature).
  template <class T>
  kernels::Population::State<T> population_state(const Ctx<T>& c, typename Work::template Scratch<T>& sc,
                                                 const T* pm) const {
    const bool wet = c.connected(wet_);
    for (int i = 0; i < n_; ++i) {
      sc.N[i] = c.x(sM_ + i) / pm[i];
      sc.floor[i] = kMassFloor / pm[i];  // an emptied class carries a finite moisture
      sc.fwet[i] = wet ? c.port(wet_, wetting::fwet(n_, i)) : T(0.0);
      sc.xwet[i] = wet ? c.port(wet_, wetting::Xwet(n_, i)) : T(0.0);
      sc.temp[i] = c.x(sT_);
    }
    kernels::Population::State<T> st;
    st.N = sc.N.data();
    st.q[0] = &c.x(sW_);
    st.floor = sc.floor.data();
    st.fields[static_cast<int>(Field::kWettedFraction)] = sc.fwet.data();
    st.fields[static_cast<int>(Field::kSpotMoisture)] = sc.xwet.data();
    st.fields[static_cast<int>(Field::kTemperature)] = sc.temp.data();
    st.p = c.p;
    return st;
  }

  // Superficial velocity from the inlet flow at inlet conditions, Eq. (77), paper 001.
  template <class T>
  T inlet_velocity(const Ctx<T>& c) const {
    const T rho_da =
        props::dry_air_partial_density(c.port(inlet_, gas::kT), c.port(inlet_, gas::kP), c.port(inlet_, gas::kY));
    return tr::superficial_velocity(T(c.port(inlet_, gas::kMdot) / rho_da), c.par(p_abed_));
  }

  // Gas-side quantities shared by all classes' drying and heat transfer.
  template <class T>
  struct GasSide {
    T t_s, t_g, y, u0, ratio, rho_da, nu, sc, pr, x_eq, y_sat, cbrt_sc, cbrt_pr;
    bool activity_capped, saturation_capped;
  };
  template <class T>
  GasSide<T> gas_side(const Ctx<T>& c, const T& t_s, const T& ratio) const {
    const T& t_g = c.port(gas_, gas::kT);
    const T& y = c.port(gas_, gas::kY);
    const T& p = c.port(gas_, gas::kP);
    GasSide<T> g{};
    g.t_s = t_s, g.t_g = t_g, g.y = y, g.u0 = c.x(sU0_), g.ratio = ratio;
    const T rho = props::humid_air_density(t_g, p, y);
    g.rho_da = props::dry_air_partial_density(t_g, p, y);  // Y is per kg dry air in Eq. (72)
    const T mu = props::air_viscosity(t_g);
    g.nu = props::kinematic_viscosity(mu, rho);
    g.sc = props::schmidt_number(mu, rho, c.par(p_dv_));                                // Eq. (78)
    g.pr = props::prandtl_number(props::humid_heat_capacity(y), mu, c.par(p_lambda_));  // Eq. (89)
    using std::cbrt;
    g.cbrt_sc = cbrt(g.sc), g.cbrt_pr = cbrt(g.pr);  // Eqs. (75), (88) for every class
    // Eqs. (82)-(83): activity of the bulk gas at the solids temperature; BET (81) is singular at a = 1
    const auto a = kernels::cap_at(p1::water_activity(y, t_s, p), T(0.99));
    g.activity_capped = a.active;
    g.x_eq = p1::bet_equilibrium_moisture(a.value, c.par(p_betmm_), c.par(p_betn_));  // Eq. (81)
    const auto ys = p1::saturation_humidity(t_s, p);  // Y_eq at T_S (docs/paper001_decisions.md), capped near boiling
    g.y_sat = ys.value;
    g.saturation_capped = ys.active;
    return g;
  }

  // The parameters of the class transfer, read once per evaluation.
  template <class T>
  struct TransferParams {
    T sh, dv, xcr, lambda;
  };
  template <class T>
  TransferParams<T> transfer_params(const Ctx<T>& c) const {
    return {c.par(p_sh_), c.par(p_dv_), c.par(p_xcr_), c.par(p_lambda_)};
  }
  // The parts of the drying rate (Eqs. (70)-(80): drying-curve factor nu, class surface, surface flux) and the
  // gas-to-solid heat flow (Eqs. (85)-(89)) of a class of diameter d_class.
  template <class T>
  static void class_transfer(const TransferParams<T>& tp, double d_class, const T& m, const T& w,
                             const T& particle_mass, const GasSide<T>& g, T* nu, T* area_out, T* flux, T* q) {
    const T di(d_class);
    const T area = kernels::class_surface(T(m / particle_mass), di);  // N_i pi d_i^2 (docs/paper001_decisions.md)
    const T re0 = tr::particle_reynolds_number(g.u0, di, g.nu);       // Eq. (76)
    using std::sqrt;
    const T sqrt_re = sqrt(re0);
    const T shb = tr::bulk_sherwood(tr::ranz_marshall_roots(sqrt_re, g.cbrt_sc), re0, g.sc, g.ratio,
                                    tp.sh);  // Eqs. (74), (75)
    const T j = p1::drying_mass_flux(g.rho_da, tr::mass_transfer_coefficient(shb, tp.dv, di), g.y_sat,
                                     g.y);                                              // Eqs. (72), (73)
    const auto eta = p1::normalized_moisture(T(w / (m + kMassFloor)), g.x_eq, tp.xcr);  // Eq. (80), regularized
    *nu = p1::linear_drying_curve(eta.value);                                           // Eq. (79)
    *area_out = area, *flux = j;
    const T nub = tr::bulk_nusselt(tr::ranz_marshall_roots(sqrt_re, g.cbrt_pr), re0, g.pr, g.ratio);  // (87), (88)
    *q = tr::heat_transfer_coefficient(nub, tp.lambda, di) * area * (g.t_g - g.t_s);                  // Eqs. (85), (86)
  }

  int n_ = def::kSizeClasses;
  ParticleParams pp_;
  std::shared_ptr<const kernels::Grid> grid_;
  kernels::Population pop_;
  BedLayering layering_;
  kernels::DryingClosures closures_;  // drying curve and drying surface
  kernels::SprayDeposition deposition_;
  kernels::StokesReport stokes_;
  ParamId p_mass_, p_x0_, p_d50_, p_sigma_, p_t0_, p_cpl_, p_abed_, p_xcr_, p_sh_, p_betmm_, p_betn_, p_dv_, p_lambda_;
  StateId sM_, sW_, sH_, sT_, sU0_, sVap_, sQ_;
  PortId wet_, gas_, inlet_, feed_;
  ParamId p_kdis_;
  StateId sRate_;  // the discharge's fraction of the hold-up per second, when the bed discharges
  ReductionId r_surface_, r_drying_, r_heat_, r_deposit_, r_capacity_, r_feed_, r_feed_water_;
  std::vector<OutputId> o_quantiles_;
  OutputId o_moisture_, o_moisture_wet_, o_particles_, o_top_, o_reg_eta_, o_reg_a_, o_water_, o_solids_, o_energy_,
      o_psd_d_, o_psd_m_, o_outside_;
  kernels::TablePsd psd_;  // a measured initial bed (settings initial_psd, initial_psd_file)
};

}  // namespace

void register_fluid_bed(Registry<Unit>& r) {
  r.add("fluid_bed", "fluid bed: population balance (aggregation, breakage), drying and heat transfer (paper 001)",
        [] { return std::make_unique<FluidBed>(); });
}

}  // namespace granuflow::units
