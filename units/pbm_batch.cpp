// Batch population balance (paper 001, Eq. (20), without flows):
//     dN_i/dt = aggregation_i(N) + breakage_i(N) + growth_i(N),     i = 0 .. n-1,
// on the flowsheet's size grid (the `particles` section), each mechanism a physical kernel plus a numerical scheme
// chosen by name in the settings, computed by the population engine (kernels/population). A mechanism not named has
// no states, parameters or cost. What leaves the grid is integrated in book-keeping states (number/volume above,
// volume below) and either removed from the population (outside = remove) or put back into the first/last class with
// its volume (outside = fold, paper 001's choice). Growth's created volume is integrated too, so the mass balance
// closes to round-off and is reported.
//
// Numbers are absolute particle counts (states N_<i>, unit "-", absolute tolerance atol * number_scale). The
// per-class fields a kernel reads (moisture, temperature ...) are parameters of the batch, equal for every class.
#include "pbm_batch.hpp"

#include <cmath>
#include <memory>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/discretization/initial_distribution.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/discretization/psd_setting.hpp"
#include "kernels/population/population.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

using namespace kernels;

enum class Initial { kExponential, kLognormalMass, kTable };

struct Work : Workspace {
  Population::WorkPtr pop;
  double volume0 = 0.0;  // on-grid volume at t = 0, m^3
  template <class T>
  struct Scratch {
    std::vector<T> rates, out, field[kFields];
    T grown;
  };
  Scratch<double> sd;
  Scratch<Jet> sj;
  template <class T>
  Scratch<T>& scratch() {
    return per_scalar<T>(sd, sj);
  }
  Population::Map map;
  bool mapped = false;
};

class PbmBatch : public UnitBase<PbmBatch> {
 public:
  std::string type() const override { return "pbm_batch"; }

  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st);
    pp_ = ps.params();
    grid_ = ps.grid();
    n_ = grid_->size();
    const double number_scale = st.get_real("number_scale", 1.0, 1e-30, 1e30,
                                            "typical particle number; absolute tolerance = atol * number_scale");
    volume_weighted_ = st.get_choice("tolerance_weighting", "volume", {"volume", "uniform"},
                                     "absolute tolerance of N_i: number_scale times min(1, x_ref / x_i), x_ref the "
                                     "mean particle volume at the start (volume: each class's volume held to the "
                                     "same level), or number_scale for every class (uniform)") == "volume";
    const std::string initial =
        st.get_choice("initial", "exponential", {"exponential", "lognormal_mass", "table"},
                      "initial distribution (table: a measured one, initial_psd_file, docs/measured_psd.md)");
    initial_ = initial == "exponential"      ? Initial::kExponential
               : initial == "lognormal_mass" ? Initial::kLognormalMass
                                             : Initial::kTable;
    binning_ = binning_from_string(st.get_choice("initial_binning", "moments", {"moments", "number", "mass"},
                                                 "how cell integrals go on the pivots"));
    if (initial_ == Initial::kExponential) {
      p_init_[0] = s.add_param({"N0", "-", 1.0, 0.0, 1e30, "initial particle number", "docs/verification.md"});
      p_init_[1] = s.add_param({"v0", "m3", 1.0, 1e-30, 1e6, "initial mean particle volume", "docs/verification.md"});
    } else if (initial_ == Initial::kTable) {
      p_init_[0] = s.add_param({"mass0", "kg", 1.0, 0.0, 1e6, "initial particle mass", "initial state (user)"});
      psd_ = read_table_psd(st, *grid_, "initial_", "initial distribution");
    } else {
      p_init_[0] = s.add_param({"mass0", "kg", 1.0, 0.0, 1e6, "initial particle mass", "initial state (user)"});
      p_init_[1] =
          s.add_param({"d50_0", "m", 200e-6, 1e-9, 1.0, "initial mass median diameter", "docs/paper001_decisions.md"});
      p_init_[2] = s.add_param(
          {"sigma_0", "-", 1.5, 1.0001, 10.0, "initial geometric standard deviation", "docs/paper001_decisions.md"});
    }
    PopulationOptions o;  // defaults: verification-oriented, mechanisms off unless named
    pop_.declare(s, st, grid_, o);
    // Per-class fields the kernels read; a batch has them as (uniform) parameters.
    const std::string batch = "batch value for every class (user)";
    const ParamSpec field_specs[kFields] = {
        {"X", "kg/kg", 0.0, 0.0, 10.0, "liquid loading of the particles", batch},
        {"X_spot", "kg/kg", 0.0, 0.0, 10.0, "moisture of the wet spots", "paper 001, Eq. (55); " + batch},
        {"T", "K", 293.15, 200.0, 700.0, "particle temperature", batch},
        {"liquid_fraction", "-", 0.0, 0.0, 1.0, "liquid volume / particle volume", "paper 002, Eq. (13); " + batch},
        {"wetted_fraction", "-", 0.0, 0.0, 1.0, "wetted fraction of the surface", "paper 001, Eq. (41); " + batch}};
    for (int f = 0; f < kFields; ++f)
      if (pop_.needs().field(static_cast<Field>(f))) p_field_[f] = s.add_param(field_specs[f]);

    sN_ = s.add_states("N", n_, StateKind::Differential, "-", number_scale);
    // checked, not constrained: the schemes keep pure aggregation and breakage non-negative by construction, and this
    // verification unit is held to exact conservation, which IDAS's constraint handling, once it acts, gives up
    s.set_nonnegative(sN_, n_, false);
    const double v_mid = grid_->pivot(n_ / 2);
    if (pop_.aggregation() || pop_.growth()) {
      s_out_[kOutNumberAbove] = s.add_accumulator("number_above", "-", number_scale);
      s_out_[kOutVolumeAbove] = s.add_accumulator("volume_above", "m3", number_scale * v_mid);
    }
    // Accumulators, not quadratures: their rates come out of the same evaluation as the population's.
    if (pop_.breakage() || pop_.growth())
      s_out_[kOutVolumeBelow] = s.add_accumulator("volume_below", "m3", number_scale * v_mid);
    if (pop_.growth()) s_grown_ = s.add_accumulator("volume_grown", "m3", number_scale * v_mid);
    s.set_classes({n_, {sN_}, {}});
    s.set_analytic_part();

    o_number_ = s.add_output("number", "-");
    o_mass_ = s.add_output("mass", "kg");
    o_d_[0] = s.add_output("d10", "m");
    o_d_[1] = s.add_output("d50", "m");
    o_d_[2] = s.add_output("d90", "m");
    o_above_ = s.add_output("mass_above", "kg");
    o_below_ = s.add_output("mass_below", "kg");
    o_grown_ = s.add_output("mass_grown", "kg");
    o_balance_ = s.add_output("mass_balance", "-");
  }

  std::unique_ptr<Workspace> workspace() const override {
    auto w = std::make_unique<Work>();
    w->pop = pop_.make_work();
    return w;
  }

  void configure(const UnitSpec& spec, const double* p, const double* shared, Workspace& ws) const override {
    Work& w = static_cast<Work&>(ws);
    pop_.configure(*w.pop, p, "unit pbm_batch");
    std::vector<double> x0(spec.states().size());
    InitCtx<double> ic{p, x0.data(), shared, &ws};
    init(ic);
    w.volume0 = volume_moment(*grid_, x0.data(), 1);
    w.mapped = false;
  }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    auto& sc = c.template ws<Work>().template scratch<T>();
    sc.rates.assign(n_, T(0.0));
    sc.out.assign(pop_.outside_rows(), T(0.0));
    sc.grown = T(0.0);
    if (!c.in_jacobian()) {
      Population::Rates<T> r;
      r.dN = sc.rates.data();
      r.outside = sc.out.data();
      r.grown = &sc.grown;
      pop_.rates(*c.template ws<Work>().pop, state(c, sc), r);
    }
    for (int i = 0; i < n_; ++i) c.res(sN_ + i) = c.xd(sN_ + i) - sc.rates[i];
    for (int k = 0; k < 3; ++k)
      if (s_out_[k]) c.res(s_out_[k]) = c.xd(s_out_[k]) - sc.out[k];
    if (s_grown_) c.res(s_grown_) = c.xd(s_grown_) - sc.grown;
    return Status::kOk;
  }

  void analytic_jacobian(const Ctx<double>& c, double, JacobianSink& sink) const override {
    Work& w = c.template ws<Work>();
    if (!w.mapped) {
      Population::Map& m = w.map;
      m = {};
      for (int i = 0; i < n_; ++i) {
        m.N_col.push_back(c.offset + sN_.i + i), m.N_scale.push_back(1.0);
        m.N_row.push_back(sN_.i + i), m.N_factor.push_back(-1.0);
      }
      m.outside_row.assign(pop_.outside_rows(), -1);
      for (int k = 0; k < 3; ++k) m.outside_row[k] = s_out_[k].i;
      m.grown_row = s_grown_.i;
      w.mapped = true;
    }
    pop_.jacobian(*w.pop, state(c, w.sd), w.map, sink);
  }

  // With a uniform number tolerance the few particles of the largest classes (volumes up to 10^9 times the start's)
  // escape the error test, and explicit methods can return their moments off by orders of magnitude without a
  // warning; held to the same volume instead, they cost 2-3 times more steps and stay right.
  void tolerance_scales(const double* p, const double*, double* scales) const override {
    if (!volume_weighted_) return;
    const double x_ref = initial_ == Initial::kExponential ? p[p_init_[1].i]
                         : initial_ == Initial::kTable     ? volume_of_diameter(psd_.d50)
                                                           : volume_of_diameter(p[p_init_[1].i]);
    for (int i = 0; i < n_; ++i) scales[sN_.i + i] *= std::min(1.0, x_ref / grid_->pivot(i));
  }

  template <class T>
  void init(InitCtx<T>& c) const {
    std::vector<T> number(n_), volume(n_);
    if (initial_ == Initial::kTable) {  // the mapped table's mass fractions on the pivots (number basis: its numbers)
      const T v_total = c.par(p_init_[0]) / pp_.envelope_density(c.shared);
      for (int i = 0; i < n_; ++i) c.x(sN_ + i) = v_total * psd_.psd.mass[i] / grid_->pivot(i);
    } else if (initial_ == Initial::kExponential)
      exponential_cells(*grid_, c.par(p_init_[0]), c.par(p_init_[1]), number.data(), volume.data());
    else
      lognormal_mass_cells(*grid_, T(c.par(p_init_[0]) / pp_.envelope_density(c.shared)), c.par(p_init_[1]),
                           c.par(p_init_[2]), number.data(), volume.data());
    if (initial_ != Initial::kTable) bin_cells(*grid_, binning_, number.data(), volume.data(), &c.x(sN_));
    for (int k = 0; k < 3; ++k)
      if (s_out_[k]) c.x(s_out_[k]) = T(0.0);
    if (s_grown_) c.x(s_grown_) = T(0.0);
  }

  template <class T>
  void outputs(const Ctx<T>& c) const {
    const T* N = &c.x(sN_);
    const T rho = pp_.envelope_density(c.shared);
    auto state_or_zero = [&](StateId s) { return s ? c.x(s) : T(0.0); };
    T number(0.0), volume(0.0);
    std::vector<T> v(n_);
    for (int i = 0; i < n_; ++i) number += N[i], v[i] = N[i] * grid_->pivot(i), volume += v[i];
    const T above = state_or_zero(s_out_[kOutVolumeAbove]), below = state_or_zero(s_out_[kOutVolumeBelow]);
    const T grown = state_or_zero(s_grown_);
    const T outside = pop_.outside() == Outside::kRemove ? T(above + below) : T(0.0);
    const double v0 = c.template ws<Work>().volume0;
    c.out(o_number_) = number;
    c.out(o_mass_) = rho * volume;
    const double q[3] = {0.1, 0.5, 0.9};
    T dq[3];
    characteristic_diameters_of_mass(grid_->diameter_edges(), v.data(), q, 3, dq);
    for (int k = 0; k < 3; ++k) c.out(o_d_[k]) = dq[k];
    c.out(o_above_) = rho * above;
    c.out(o_below_) = rho * below;
    c.out(o_grown_) = rho * grown;
    c.out(o_balance_) = v0 > 0 ? T((volume + outside - grown - v0) / v0) : T(0.0);
  }

 private:
  template <class T>
  Population::State<T> state(const Ctx<T>& c, typename Work::template Scratch<T>& sc) const {
    Population::State<T> st;
    st.N = &c.x(sN_);
    st.p = c.p;
    for (int f = 0; f < kFields; ++f)
      if (p_field_[f]) {
        sc.field[f].assign(n_, c.par(p_field_[f]));
        st.fields[f] = sc.field[f].data();
      }
    return st;
  }

  ParticleParams pp_;
  std::shared_ptr<const Grid> grid_;
  int n_ = 0;
  Initial initial_ = Initial::kExponential;
  TablePsd psd_;  // initial: table
  bool volume_weighted_ = true;
  Binning binning_ = Binning::kMoments;
  Population pop_;
  ParamId p_init_[3], p_field_[kFields];
  StateId sN_, s_out_[3], s_grown_;
  OutputId o_number_, o_mass_, o_d_[3], o_above_, o_below_, o_grown_, o_balance_;
};

}  // namespace

void register_pbm_batch(Registry<Unit>& r) {
  r.add("pbm_batch", "batch population balance: aggregation, breakage, growth by named kernels and schemes",
        [] { return std::make_unique<PbmBatch>(); });
}

}  // namespace granuflow::units
