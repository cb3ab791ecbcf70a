// ParticleChamber's declarations (particle_chamber.hpp): settings, parameters, mechanisms, states and ports with the
// outlets' companions, the Jacobian's class structure, outputs.
#include <string>
#include <tuple>

#include "chamber_outlet.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/paper001_defaults.hpp"
#include "kernels/registry.hpp"
#include "particle_chamber.hpp"

namespace granuflow::units {

using kernels::Field;

void ParticleChamber::declare(UnitSpec& s, Settings& st) {
  const ParticleSystem& ps = particle_system(s, st, true);
  pp_ = ps.params();
  grid_ = ps.grid();
  n_ = grid_->size();
  K_ = pp_.component_count();
  declare_options(ps, st);
  declare_composition(s, st);
  declare_params(s, st);
  declare_mechanisms(s, st);
  declare_states_and_ports(s);
  declare_structure(s);
  declare_outputs(s);
}

void ParticleChamber::declare_options(const ParticleSystem& ps, Settings& st) {
  spray_ = role_ != ChamberRole::kDryingZone;
  if (role_ == ChamberRole::kGranulator)
    spray_ = st.get_choice("spray", "layering", {"layering", "none"},
                           "layering growth from the spray (paper 003, Eq. (7.33)) or no spray (a drying or "
                           "residence-time segment)") == "layering";
  wet_ = st.get_choice("drying", "none", {"none", "first_order"},
                       "water on the particles: none (sprayed and fed water evaporates at once) or per-class water "
                       "drying at (W - X_eq M) / tau_dry (or along drying_curve)") == "first_order";
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
    if (controlled_)
      located_valve_ = st.get_choice("valve", "smooth", {"smooth", "located"},
                                     "the controlled discharge's switches (closed below zero demand, at capacity "
                                     "above mdot_max): smooth, or located: set by the parameter valve, which the "
                                     "scene's events switch where discharge_demand crosses them") == "located";
  }
}

void ParticleChamber::declare_params(UnitSpec& s, Settings& st) {
  const std::string op = "operating input", init = "initial state (user)";
  p_mass_ = s.add_param(
      {"bed_mass", "kg", role_ == ChamberRole::kSprayZone ? 0.08 : 4.0, 0.0, 1e5, "initial dry solids hold-up", init});
  psd_ = kernels::declare_table_psd(st, *grid_, "initial_", "initial bed");
  if (!psd_.table) {
    p_d50_ = s.add_param({"d50_0", "m", 1.8e-3, 1e-7, 1.0, "initial mass median diameter (log-normal in mass)", init});
    p_sigma_ = s.add_param({"sigma_0", "-", 1.15, 1.001, 10.0, "initial geometric standard deviation", init});
  }
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
    closures_.declare(s, st, "", false);  // paper 000, section 5.4.1: a drying curve instead of first order
    if (closures_.has_curve())
      p_xcr_ = s.add_param({"X_cr", "kg/kg", kernels::paper001::defaults::kCriticalMoisture, 1e-4, 10.0,
                            "critical moisture content: end of the constant-rate period", "paper 001, Table 8"});
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
    if (located_valve_)
      p_valve_ = s.add_param({"valve", "-", 1.0, 0.0, 2.0,
                              "valve position: 0 closed, 1 following the demand, 2 at capacity (set by events)", op});
  }
  if (discharge_ == Discharge::kClassified)
    classifier_.declare(s, st, "classifier", "plitt", "class_", "separation curve of the classifying discharge", grid_,
                        1e-3);
}

void ParticleChamber::declare_mechanisms(UnitSpec& s, Settings& st) {
  // Aggregation and breakage by the engine (growth is the unit's own layering); particles leaving the grid stay
  // in the end classes.
  kernels::PopulationOptions o;
  o.growth = "";
  o.outside = kernels::Outside::kFold;
  if (wet_) o.properties = {"water"};
  for (int k = 1; k < K_; ++k) o.properties.push_back("m_" + pp_.components[k]);
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
}

void ParticleChamber::declare_states_and_ports(UnitSpec& s) {
  sM_ = s.add_states("M", n_, StateKind::Differential, "kg", 1.0);
  if (wet_) sW_ = s.add_states("W", n_, StateKind::Differential, "kg", 0.1);
  sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
  if (!wet_) sZero_ = s.add_state("water_out", StateKind::Algebraic, "kg/s", 1e-3);  // dry outlets carry none
  const auto& d = grid_->diameter_pivots();
  for (int k = 1; k < K_; ++k)
    sQ_.push_back(s.add_states("m_" + pp_.components[k], n_, StateKind::Differential, "kg", 1.0));
  auto inlet = [&](const std::string& name, bool optional) {
    const PortId p = s.add_port(name, streams::solids(K_), PortDir::In, n_, optional);
    s.set_port_grid(p, d);
    inlets_.push_back(p);
  };
  auto outlet = [&](const std::string& name, Outlet& o) {
    o.rate = s.add_state(name + "_rate", StateKind::Algebraic, "1/s", 1e-3);
    o.holdup = s.add_port(name + "_holdup", chamber_holdup(K_), PortDir::Out, n_);
    s.set_port_grid(o.holdup, d);
    for (int i = 0; i < n_; ++i) {
      s.provide(o.holdup, holdup_fields::mass(i), sM_ + i);
      s.provide(o.holdup, holdup_fields::water(n_, i), wet_ ? sW_ + i : sZero_);
    }
    for (int k = 1; k < K_; ++k)
      for (int i = 0; i < n_; ++i) s.provide(o.holdup, holdup_fields::component(n_, k, i), sQ_[k - 1] + i);
    s.provide(o.holdup, holdup_fields::T(n_), sT_);
    s.provide(o.holdup, holdup_fields::rate(n_), o.rate);
    ChamberOutletSpec spec{
        n_, wet_, &o == &discharge_out_ && discharge_ == Discharge::kClassified ? &classifier_ : nullptr, d, K_};
    s.add_companion(
        {name, [spec](const std::string& owner) { return make_chamber_outlet(owner, spec); }, o.holdup, name});
  };
  if (role_ != ChamberRole::kGranulator) {
    inlet("in", false);
    outlet("out", exchange_);
  }
  if (role_ != ChamberRole::kSprayZone) inlet("feed", true);
  if (discharge_ != Discharge::kNone) outlet("discharge", discharge_out_);
}

void ParticleChamber::declare_structure(UnitSpec& s) {
  if (composed()) {  // layering and the engine couple the classes: plain forward AD over every column
    if (spray_ && wet_) r_surface_ = s.add_reduction("particle surface");
    if (controlled_) {
      r_mass_ = s.add_reduction("hold-up");
      if (discharge_ == Discharge::kClassified) r_tm_ = s.add_reduction("classifier-weighted hold-up");
      r_in_ = s.add_reduction("solids fed");
    }
    return;
  }
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
}

void ParticleChamber::declare_outputs(UnitSpec& s) {
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
  if (located_valve_) o_demand_ = s.add_output("discharge_demand", "kg/s");
  if (exchange_.rate) o_exch_ = s.add_output("exchange_mdot", "kg/s");
  o_top_ = s.add_output("top_class_fraction", "-", OutputRole::kGridEnd);
  o_heat_ = s.add_output("heat_duty", "W");
  o_vapour_ = s.add_output("vapour_mdot", "kg/s");
  o_hold_solids_ = s.add_output("balance_solids_hold", "kg", OutputRole::kBalanceHold, "solids");
  o_hold_water_ = s.add_output("balance_water_hold", "kg", OutputRole::kBalanceHold, "water");
  o_hold_energy_ = s.add_output("balance_energy_hold", "J", OutputRole::kBalanceHold, "energy");
  std::tie(o_psd_d_, o_psd_m_) = s.add_size_distribution(n_, grid_->diameter_edges());
  if (psd_.table) o_outside_ = s.add_output("initial_psd_outside", "-");  // measured mass folded into end classes
  if (!composed()) return;
  for (int k = 0; k < K_; ++k) {
    const std::string& name = pp_.components[k];
    o_comp_mass_.push_back(s.add_output("mass_" + name, "kg"));
    o_comp_hold_.push_back(s.add_output("balance_" + name + "_hold", "kg", OutputRole::kBalanceHold, "solids:" + name));
    o_comp_class_.push_back(s.add_output(name + "_mass_0", "kg", OutputRole::kValue, "", 0));
    for (int i = 1; i < n_; ++i) s.add_output(name + "_mass_" + std::to_string(i), "kg", OutputRole::kValue, "", i);
  }
  if (spray_)
    q_comp_in_ = s.add_quadrature("balance_" + pp_.components[layer_] + "_in", "kg", 1.0, OutputRole::kBalanceIn,
                                  "solids:" + pp_.components[layer_]);
}

void ParticleChamber::declare_composition(UnitSpec&, Settings& st) {
  if (!spray_) return;
  const std::string name = st.get_choice("spray_component", "", {},
                                         "the component of the particle system the sprayed solids are (particles: "
                                         "settings: components); empty: the first");
  if (name.empty()) return;
  layer_ = pp_.component(name);
  if (layer_ < 0) {
    std::string known;
    for (const auto& c : pp_.components) known += (known.empty() ? "" : ", ") + c;
    throw ConfigError(st.where() + ".spray_component = '" + name + "': the particle system has the components " +
                      known + " (particles: settings: components)");
  }
}

}  // namespace granuflow::units
