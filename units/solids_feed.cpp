#include "solids_feed.hpp"

#include <cmath>

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/discretization/psd_setting.hpp"
#include "kernels/paper001_defaults.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

// Explicit: the stream follows the parameters; what it feeds is integrated as quadratures.
class SolidsFeed : public UnitBase<SolidsFeed> {
 public:
  std::string type() const override { return "solids_feed"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    pp_ = ps.params();
    grid_ = ps.grid();
    n_ = grid_->size();
    p_m_ = s.add_param({"mdot", "kg/s", 1e-3, 0.0, 1e3, "dry-solids mass flow", "operating input"});
    psd_ = kernels::declare_table_psd(st, *grid_, "", "feed");
    if (!psd_.table) {
      p_d50_ =
          s.add_param({"d50", "m", 300e-6, 1e-7, 1.0, "mass median diameter (log-normal in mass)", "operating input"});
      p_sigma_ = s.add_param({"sigma", "-", 1.3, 1.01, 10.0, "geometric standard deviation", "operating input"});
    }
    p_x_ = s.add_param({"X", "kg/kg", 0.0, 0.0, 10.0, "moisture, dry basis", "operating input"});
    p_t_ = s.add_param({"T", "K", 293.15, 200.0, 700.0, "temperature", "operating input"});
    p_cpl_ = s.add_param({"cp_l", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 100.0, 1e4,
                          "heat capacity of the water carried", "paper 001, Table 6"});
    wet_ = ps.water();
    sM_ = s.add_states("mdot", n_, StateKind::Algebraic, "kg/s", 1e-3);
    // a dry feed's water fields are one zero (the particle system carries none)
    sW_ = wet_ ? s.add_states("water", n_, StateKind::Algebraic, "kg/s", 1e-4)
               : s.add_state("water", StateKind::Algebraic, "kg/s", 1e-4);
    sT_ = s.add_state("T", StateKind::Algebraic, "K", 300.0);
    s.set_explicit();
    const PortId out = s.add_port("out", streams::solids(pp_.component_count()), PortDir::Out, n_);
    s.set_port_grid(out, grid_->diameter_pivots());
    if (wet_) {
      for (int f = 0; f <= 2 * n_; ++f) s.provide(out, f, sM_ + f);  // mdot, water, T: consecutive states
      s.set_classes({n_, {sM_, sW_}, {}});
    } else {
      for (int i = 0; i < n_; ++i) s.provide(out, solids::mdot(i), sM_ + i), s.provide(out, solids::water(n_, i), sW_);
      s.provide(out, solids::T(n_), sT_);
      s.set_classes({n_, {sM_}, {}});
    }
    q_solids_ = s.add_quadrature("balance_solids_in", "kg", 1.0, OutputRole::kBalanceIn, "solids");
    q_water_ = s.add_quadrature("balance_water_in", "kg", 0.1, OutputRole::kBalanceIn, "water");
    q_energy_ = s.add_quadrature("balance_energy_in", "J", 1e5, OutputRole::kBalanceIn, "energy");
    if (pp_.component_count() > 1) declare_component(s, st, out);
  }
  // A composed particle system (particles.hpp): the feed is of one named solid (setting component), the flows of the
  // others zero.
  void declare_component(UnitSpec& s, Settings& st, PortId out) {
    const std::string name =
        st.get_choice("component", pp_.components[0], pp_.components, "the named solid the feed is made of");
    const int fed = pp_.component(name);
    sZero_ = s.add_state("zero", StateKind::Algebraic, "kg/s", 1e-3);
    for (int k = 1; k < pp_.component_count(); ++k)
      for (int i = 0; i < n_; ++i) s.provide(out, solids::component(n_, k, i), k == fed ? sM_ + i : sZero_);
    q_comp_ = s.add_quadrature("balance_" + name + "_in", "kg", 1.0, OutputRole::kBalanceIn, "solids:" + name);
  }
  void check(const UnitSpec&, const double* p) const override {
    if (!wet_ && p[p_x_.i] != 0.0)
      throw ConfigError(violation("X", p[p_x_.i], "kg/kg", "0: the particle system is dry (particles: water: false)"));
  }
  // Mass fraction of class i of a log-normal mass distribution over the cells (tails in the end classes).
  template <class T>
  T fraction(int i, const T* p) const {
    if (psd_.table) return T(psd_.psd.mass[i]);  // a measured table, mapped in declare
    using std::erfc, std::log;
    const auto& de = grid_->diameter_edges();
    auto cdf = [&](int e) { return T(0.5 * erfc(-log(de[e] / p[p_d50_.i]) / (log(p[p_sigma_.i]) * std::sqrt(2.0)))); };
    const T lo = i == 0 ? T(0.0) : cdf(i), hi = i == n_ - 1 ? T(1.0) : cdf(i + 1);
    return hi - lo;
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    for (int i = 0; i < n_; ++i) {
      const T m = c.par(p_m_) * fraction(i, c.p);
      c.res(sM_ + i) = c.x(sM_ + i) - m;
      if (wet_) c.res(sW_ + i) = c.x(sW_ + i) - m * c.par(p_x_);
    }
    if (!wet_) c.res(sW_) = c.x(sW_);
    if (sZero_) c.res(sZero_) = c.x(sZero_);
    c.res(sT_) = c.x(sT_) - c.par(p_t_);
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    T m(0.0), w(0.0);
    for (int i = 0; i < n_; ++i) m += c.x(sM_ + i), w += wet_ ? c.x(sW_ + i) : T(0.0);
    c.r[q_solids_.i] = m;
    c.r[q_water_.i] = w;
    if (q_comp_) c.r[q_comp_.i] = m;
    c.r[q_energy_.i] = (m * c.sh(pp_.cp_s) + w * c.par(p_cpl_)) * (c.x(sT_) - props::kT0);
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    for (int i = 0; i < n_; ++i) {
      c.x(sM_ + i) = c.par(p_m_) * fraction(i, c.p);
      if (wet_) c.x(sW_ + i) = c.x(sM_ + i) * c.par(p_x_);
    }
    if (!wet_) c.x(sW_) = T(0.0);
    if (sZero_) c.x(sZero_) = T(0.0);
    c.x(sT_) = c.par(p_t_);
  }

 private:
  int n_ = 0;
  bool wet_ = true;  // the particle system carries water
  ParticleParams pp_;
  std::shared_ptr<const kernels::Grid> grid_;
  kernels::TablePsd psd_;  // settings psd, psd_file
  ParamId p_m_, p_d50_, p_sigma_, p_x_, p_t_, p_cpl_;
  StateId sM_, sW_, sT_, sZero_;
  QuadId q_solids_, q_water_, q_energy_, q_comp_;
};

}  // namespace

void register_solids_feed(Registry<Unit>& r) {
  r.add("solids_feed", "solids feed: mass flow with a log-normal size distribution, moisture, temperature",
        [] { return std::make_unique<SolidsFeed>(); });
}

}  // namespace granuflow::units
