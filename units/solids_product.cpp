#include "solids_product.hpp"

#include <string>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/properties.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/paper001_defaults.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

class SolidsProduct : public UnitBase<SolidsProduct> {
 public:
  std::string type() const override { return "solids_product"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    pp_ = ps.params();
    grid_ = ps.grid();
    n_ = grid_->size();
    p_cpl_ = s.add_param({"cp_l", "J/(kg K)", kernels::paper001::defaults::kLiquidCp, 100.0, 1e4,
                          "heat capacity of the water carried", "paper 001, Table 6"});
    in_ = s.add_port("in", streams::solids(pp_.component_count()), PortDir::In, n_);
    s.set_port_grid(in_, grid_->diameter_pivots());
    q_solids_ = s.add_quadrature("balance_solids_out", "kg", 1.0, OutputRole::kBalanceOut, "solids");
    q_water_ = s.add_quadrature("balance_water_out", "kg", 0.1, OutputRole::kBalanceOut, "water");
    q_energy_ = s.add_quadrature("balance_energy_out", "J", 1e5, OutputRole::kBalanceOut, "energy");
    // a composed particle system (particles.hpp): what arrives of each named solid (the first's is the rest)
    for (int k = 0; k < pp_.component_count() && pp_.component_count() > 1; ++k) {
      const std::string& name = pp_.components[k];
      q_comp_.push_back(
          s.add_quadrature("balance_" + name + "_out", "kg", 1.0, OutputRole::kBalanceOut, "solids:" + name));
    }
    o_mdot_ = s.add_output("mdot", "kg/s");
    for (const char* o : {"d10", "d50", "d90"}) o_d_.push_back(s.add_output(o, "m"));
  }
  template <class T>
  Status eval(const Ctx<T>&) const {
    return Status::kOk;
  }
  template <class T>
  void quad(const Ctx<T>& c) const {
    T m(0.0), w(0.0);
    for (int i = 0; i < n_; ++i) m += c.port(in_, solids::mdot(i)), w += c.port(in_, solids::water(n_, i));
    c.r[q_solids_.i] = m;
    c.r[q_water_.i] = w;
    if (!q_comp_.empty()) {
      T first = m;
      for (size_t k = 1; k < q_comp_.size(); ++k) {
        T q(0.0);
        for (int i = 0; i < n_; ++i) q += c.port(in_, solids::component(n_, static_cast<int>(k), i));
        c.r[q_comp_[k].i] = q;
        first -= q;
      }
      c.r[q_comp_[0].i] = first;
    }
    c.r[q_energy_.i] = (m * c.sh(pp_.cp_s) + w * c.par(p_cpl_)) * (c.port(in_, solids::T(n_)) - props::kT0);
  }
  template <class T>
  void init(InitCtx<T>&) const {}
  // The stream arriving: its flow and mass-based characteristic diameters.
  template <class T>
  void outputs(const Ctx<T>& c) const {
    std::vector<T> m(n_);
    T total(0.0);
    for (int i = 0; i < n_; ++i) m[i] = c.port(in_, solids::mdot(i)), total += m[i];
    c.out(o_mdot_) = total;
    const double q[3] = {0.1, 0.5, 0.9};
    T dq[3];  // undefined while nothing arrives
    kernels::characteristic_diameters_of_mass(grid_->diameter_edges(), m.data(), q, 3, dq);
    for (int k = 0; k < 3; ++k) c.out(o_d_[k]) = dq[k];
  }

 private:
  int n_ = 0;
  ParticleParams pp_;
  std::shared_ptr<const kernels::Grid> grid_;
  ParamId p_cpl_;
  PortId in_;
  QuadId q_solids_, q_water_, q_energy_;
  std::vector<QuadId> q_comp_;
  OutputId o_mdot_;
  std::vector<OutputId> o_d_;
};

}  // namespace

void register_solids_product(Registry<Unit>& r) {
  r.add("solids_product", "solids sink: integrates the solids, water and enthalpy it receives",
        [] { return std::make_unique<SolidsProduct>(); });
}

}  // namespace granuflow::units
