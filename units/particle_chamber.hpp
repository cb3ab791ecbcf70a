// A well-mixed compartment of a spray fluidized bed holding a particle population on the flowsheet's size grid: the
// shared implementation of the paper-003 units granulator (a whole continuous chamber), spray_compartment and
// drying_compartment (the two zones of Eqs. (7.37)-(7.39)). Not registered itself; each unit file chooses a Role.
//
// States per class i: dry solids M_i (kg), optionally water W_i (kg, setting drying: first_order); per outlet one
// rate r (algebraic, 1/s). An outlet's flows r_i M_i and r_i W_i are computed by the outlet's companion unit
// (chamber_outlet.hpp, "<chamber>:<outlet>"), inline, so they are no unknowns of the Newton system. Mechanisms:
//  * layering growth from a spray (granulator, spray compartment): the sprayed solids M_sus = m_spray w_spray spread
//    over the particle surface, G = 2 M_sus / (rho pi mu_2) the same for every particle (paper 003, Eqs.
//    (7.32)-(7.34)), on the finite-volume scheme of the population engine (kernels/discretization/fv_growth.hpp)
//    normalized so that the population gains exactly M_sus kg/s; rho is the particles' envelope density, so layer and
//    core are alike;
//  * aggregation and breakage by the population engine (settings aggregation, breakage; off by default);
//  * composition, when the particle system names several solids (particles.hpp): per class the mass Q_c,i of each
//    component after the first is a state as well (the first's is M_i minus theirs), carried as an extensive property
//    of the population engine (moved with volume by aggregation and breakage); the number of a class follows from
//    its volume, N_i = (sum_c m_c,i / rho_c) / x_i. Layering moves every component with the number fluxes from the
//    donor cell and deposits the sprayed solid (setting spray_component) with its own density, so that each class's
//    volume changes exactly as the finite-volume scheme moves it. The initial hold-up is of the first component.
//  * drying: the sprayed water lands on the classes in proportion to their surface and dries at the rate
//    (W_i - X_eq M_i) / tau_dry (a lumped first-order drying kinetics), or, with drying: none, evaporates at once;
//  * outlets (every class leaves at a rate r_i, carrying its water, M_i r_i and W_i r_i):
//      exchange (compartments): r_i = 1 / tau, the mean residence time of the compartment (Eqs. (7.37), (7.38));
//      discharge unclassified: r_i = r, classified: r_i = r T_i with the cell fractions T_i of a separation curve
//      (a classifying discharge: sifter, counter-current tube); r = k_discharge (bed mass free), or, with the bed
//      mass held by a discharge controller, chosen so that the discharge R = sum_i r_i M_i is
//          R = min(softplus(u), mdot_max),  u = (inflows + M_sus - other outflows) + (M - M_set) / tau_c,
//      an ideal level controller (discharge = inflow) with a proportional correction, limited by the capacity of
//      the discharge; softplus(u) = (u + sqrt(u^2 + eps^2)) / 2, eps = 1e-3 M_set / tau_c, keeps the valve from
//      opening backwards while the bed fills at start-up and leaves the steady bed mass within eps^2 tau_c / (4 R)
//      of M_set; the minimum has the same smooth form, min(a, b) = a - softplus(a - b). With a recycle the inflow
//      includes the recycle, which depends on the discharge: the equations are solved together (an algebraic loop),
//      With the setting valve: located, the switches are not smoothed: R = 0, u or mdot_max by the parameter `valve`
//      (0 closed, 1 following the demand u, 2 at capacity), which the scene's events switch where the reported
//      demand u (output discharge_demand) crosses 0 or mdot_max, located by the integrator
//      (docs/events_and_checkpoints.md).
//      and while the bed holds few particles of product size the ideal controller circulates R = M_sus / (product
//      fraction), which the capacity bounds.
// The bed is isothermal at T_bed (held by the fluidization gas, which is not modelled): the heat the gas supplies is
// reported as a balance term (energy in), so the flowsheet's energy balance closes.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "classifier.hpp"
#include "granuflow/signals.hpp"
#include "granuflow/unit.hpp"
#include "kernels/discretization/fv_growth.hpp"
#include "kernels/discretization/psd_setting.hpp"
#include "kernels/drying/drying_closures.hpp"
#include "kernels/population/population.hpp"
#include "particles.hpp"

namespace granuflow::units {

enum class ChamberRole { kGranulator, kSprayZone, kDryingZone };

class ParticleChamber : public UnitBase<ParticleChamber>, public HoldsSetPoint {
 public:
  explicit ParticleChamber(ChamberRole role) : role_(role) {}
  std::string type() const override;
  void declare(UnitSpec& s, Settings& st) override;
  std::unique_ptr<Workspace> workspace() const override;
  void configure(const UnitSpec& spec, const double* p, const double* shared, Workspace& ws) const override;
  void check(const UnitSpec& spec, const double* p) const override;
  void analytic_jacobian(const Ctx<double>& c, double cj, JacobianSink& sink) const override;
  // With the bed mass held (ideal level controller), its dry mass at M_set (a steady state says when it is not).
  std::vector<SetPoint> set_points() const override {
    if (!controlled_) return {};
    return {{p_mset_, o_mass_}};
  }

  template <class T>
  Status eval(const Ctx<T>& c) const;
  template <class T>
  T valve_flow(const Ctx<T>& c, const T& u, const T& m_set, const T& tau_c) const;
  template <class T>
  void init(InitCtx<T>& c) const;
  template <class T>
  void outputs(const Ctx<T>& c) const;
  template <class T>
  void quad(const Ctx<T>& c) const;

  enum class Discharge { kNone, kUnclassified, kClassified };
  struct Work;

 private:
  struct Outlet {
    PortId holdup;  // what the outlet's companion reads: the hold-up and the rate
    StateId rate;   // 1/s: class i leaves at rate * f_i (f_i: the classifier's fractions, or 1)
  };
  // The declarations, in their order: settings, parameters, the population engine and the growth scheme, states
  // and ports (with the outlets' companions), the Jacobian's class structure and reductions, outputs.
  void declare_options(const ParticleSystem& ps, Settings& st);
  void declare_params(UnitSpec& s, Settings& st);
  void declare_mechanisms(UnitSpec& s, Settings& st);
  void declare_states_and_ports(UnitSpec& s);
  void declare_structure(UnitSpec& s);
  void declare_outputs(UnitSpec& s);
  // The outlets in a fixed order (exchange, discharge): index k of the outflow arrays of the workspace.
  static constexpr int kOutlets = 2;
  const Outlet& outlet(int k) const { return k == 0 ? exchange_ : discharge_out_; }
  template <class T>
  const T* discharge_fractions(const Ctx<T>& c) const;  // nullptr unless the discharge classifies
  // Every outlet's flows per class, solids r_i M_i and water r_i W_i (the same operations as the outlet's companion,
  // chamber_outlet.hpp), once per evaluation into the workspace's arrays om[k], ow[k] that the balances (eval), the
  // outputs and the boundary terms read.
  template <class T>
  void outflows(const Ctx<T>& c, const T* frac) const;
  // What crosses the flowsheet's boundary in this unit per second (quad(), outputs()).
  template <class T>
  struct Boundary {
    T water_in, vapour, h_spray, h_vapour, energy_in;
  };
  template <class T>
  Boundary<T> boundary(const Ctx<T>& c) const;  // computes the outflows (outflows()) for its caller too
  template <class T>
  T spray_solids(const Ctx<T>& c) const;
  // Water drying off a class of m kg dry solids holding w kg water, kg/s: first order, or along a drying curve.
  template <class T>
  T drying_rate(const Ctx<T>& c, const T& m, const T& w) const;
  template <class T>
  void growth_rates(const Ctx<T>& c, const T* N, const T* W, const T& amount, T* dM, T* dW) const;
  // What the inlets bring per class (dry solids, water), summed over the inlets in their order.
  template <class T>
  void inlet_flows(const Ctx<T>& c, T* in_m, T* in_w, std::vector<T>& gather) const;
  // Composition (K_ > 1): class numbers from the component volumes, layering of the sprayed component, the
  // engine's property rates turned into mass rates (particle_chamber_composition.cpp).
  template <class T>
  void class_numbers(const Ctx<T>& c, const T* pm, T* N) const;
  template <class T>
  void composed_growth(const Ctx<T>& c, const T* N, const T* W, const T& amount, T* dM, T* dQ, T* dW) const;
  template <class T>
  void composed_engine(const Ctx<T>& c, const T* dN, const T* dq, T* dM, T* dQ) const;
  template <class T>
  void composed_residuals(const Ctx<T>& c) const;
  template <class T>
  void composed_outputs(const Ctx<T>& c) const;
  void declare_composition(UnitSpec& s, Settings& st);
  bool composed() const { return K_ > 1; }
  template <class T>
  kernels::Population::State<T> population_state(const Ctx<T>& c, const T* N, const T* floor, T* temp) const;

  ChamberRole role_;
  int n_ = 0;
  int K_ = 1, layer_ = 0;    // components, and the one the spray deposits
  std::vector<StateId> sQ_;  // per component c >= 1 its class masses (sQ_[c - 1])
  std::vector<OutputId> o_comp_mass_, o_comp_hold_, o_comp_class_;
  QuadId q_comp_in_;
  ParticleParams pp_;
  std::shared_ptr<const kernels::Grid> grid_;
  std::unique_ptr<kernels::FvGrowth> fv_;  // layering growth, when the unit sprays
  kernels::Population pop_;                // aggregation and breakage
  bool spray_ = false, wet_ = false;
  Discharge discharge_ = Discharge::kNone;
  bool controlled_ = false;
  bool located_valve_ = false;  // valve: located (the discharge's switches as events, not smoothed)
  Classifier classifier_;
  kernels::DryingClosures closures_;  // the drying curve (setting drying_curve), when one is chosen
  ParamId p_xcr_;                     // its critical moisture
  ParamId p_mass_, p_d50_, p_sigma_, p_x0_, p_t_, p_cpl_;
  ParamId p_spray_, p_w_, p_tspray_, p_taudry_, p_xeq_, p_tau_, p_k_, p_mset_, p_tauc_, p_rmax_, p_valve_;
  StateId sM_, sW_, sT_, sZero_;
  std::vector<PortId> inlets_;
  Outlet exchange_, discharge_out_;
  ReductionId r_mass_, r_tm_, r_in_, r_surface_;
  QuadId q_solids_in_, q_water_in_, q_water_out_, q_energy_in_, q_energy_out_;
  OutputId o_demand_;
  OutputId o_mass_, o_moisture_, o_d_[3], o_d32_, o_dmean_, o_sigma_, o_g_, o_particles_, o_dis_, o_exch_, o_top_,
      o_heat_, o_vapour_, o_hold_solids_, o_hold_water_, o_hold_energy_, o_psd_d_, o_psd_m_, o_outside_;
  kernels::TablePsd psd_;  // a measured initial bed (settings initial_psd, initial_psd_file)
};

}  // namespace granuflow::units
