// Two-deck screen (paper 003, section 7.5.1: the product is the fraction between the decks, oversize and undersize
// are recycled). Zero hold-up, explicit: per size class i with the decks' cell fractions T_up,i and T_lo,i (the
// separation curves averaged over the class, kernels/classification/separation_curve.hpp),
//     oversize_i = T_up,i in_i,   product_i = T_lo,i (in_i - oversize_i),   undersize_i = in_i - oversize_i -
//     product_i,
// so the three outlets add up to the feed class by class (to one rounding), water and each named solid of a composed
// particle system (particles.hpp) go with the solids of their class, and the temperature passes through. With the sharp
// curve the decks split exactly at their cut sizes.
#include "sieve.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "classifier.hpp"
#include "granuflow/flowsheet.hpp"
#include "particles.hpp"

namespace granuflow::units {
namespace {

struct Work : Workspace {
  Classifier::Cache upper, lower;
  std::vector<double> in_d;  // the feed gathered where its fields are not consecutive (Ctx::port_array)
  std::vector<Jet> in_j;
};

class Sieve : public UnitBase<Sieve> {
 public:
  std::string type() const override { return "sieve"; }
  void declare(UnitSpec& s, Settings& st) override {
    const ParticleSystem& ps = particle_system(s, st, true);
    grid_ = ps.grid();
    n_ = grid_->size();
    upper_.declare(s, st, "upper_curve", "plitt", "upper_", "separation curve of the upper deck (oversize)", grid_,
                   2e-3);
    lower_.declare(s, st, "lower_curve", "plitt", "lower_", "separation curve of the lower deck (product)", grid_,
                   1e-3);
    K_ = ps.params().component_count();
    in_ = s.add_port("in", streams::solids(K_), PortDir::In, n_);
    const char* names[3] = {"oversize", "product", "undersize"};
    out_.declare(s, ps, in_, {names[0], names[1], names[2]});
    for (int o = 0; o < 3; ++o) o_m_[o] = s.add_output(std::string(names[o]) + "_mdot", "kg/s");
    o_frac_ = s.add_output("product_fraction", "-");
  }
  void check(const UnitSpec&, const double* p) const override {
    if (!(p[lower_.d_cut_index()] < p[upper_.d_cut_index()]))
      throw ConfigError(violation("lower_d_cut", p[lower_.d_cut_index()], "m",
                                  "lower_d_cut < upper_d_cut (" + fmt_num(p[upper_.d_cut_index()]) + " m)"));
  }
  std::unique_ptr<Workspace> workspace() const override { return std::make_unique<Work>(); }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    Work& w = c.template ws<Work>();
    const T* tu = upper_.fractions(c.p, w.upper);
    const T* tl = lower_.fractions(c.p, w.lower);
    auto& scratch = per_scalar<T>(w.in_d, w.in_j);
    split(c, tu, tl, c.port_array(in_, solids::mdot(0), n_, scratch), out_.m);
    if (out_.wet) split(c, tu, tl, c.port_array(in_, solids::water(n_, 0), n_, scratch), out_.w);
    for (int k = 1; k < K_; ++k) {
      const StateId q[3] = {out_.q[0][k - 1], out_.q[1][k - 1], out_.q[2][k - 1]};
      split(c, tu, tl, c.port_array(in_, solids::component(n_, k, 0), n_, scratch), q);
    }
    return Status::kOk;
  }
  // One field's three outlets (states s[0..2]) from the feed's array `in`: over = t_u in, product = t_l (in - over),
  // undersize the rest.
  template <class T>
  void split(const Ctx<T>& c, const T* tu, const T* tl, const T* in, const StateId s[3]) const {
    const T *x0 = &c.x(s[0]), *x1 = &c.x(s[1]), *x2 = &c.x(s[2]);
    T *r0 = &c.res(s[0]), *r1 = &c.res(s[1]), *r2 = &c.res(s[2]);
    // residuals, states and inputs are separate arrays: without saying so (omp simd) the six inputs and three
    // outputs need more run-time alias checks than GCC makes, and the loop stayed scalar
#pragma omp simd
    for (int i = 0; i < n_; ++i) {
      const T over = tu[i] * in[i];
      const T prod = tl[i] * (in[i] - over);
      r0[i] = x0[i] - over;
      r1[i] = x1[i] - prod;
      r2[i] = x2[i] - (in[i] - over - prod);
    }
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    out_.init(c, n_);
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    T m[3] = {T(0.0), T(0.0), T(0.0)};
    for (int o = 0; o < 3; ++o)
      for (int i = 0; i < n_; ++i) m[o] += c.x(out_.m[o] + i);
    for (int o = 0; o < 3; ++o) c.out(o_m_[o]) = m[o];
    const T total = m[0] + m[1] + m[2];
    // the share of nothing is undefined, not 0 (NaN in the time series, null in a summary)
    c.out(o_frac_) = total > 0.0 ? T(m[1] / total) : T(std::nan(""));
  }

 private:
  int n_ = 0;
  int K_ = 1;  // named solids
  std::shared_ptr<const kernels::Grid> grid_;
  Classifier upper_, lower_;
  PortId in_;
  SolidsOutlets out_;
  OutputId o_m_[3], o_frac_;
};

}  // namespace

void register_sieve(Registry<Unit>& r) {
  r.add("sieve", "two-deck screen: oversize, product and undersize by one separation curve per deck (paper 003)",
        [] { return std::make_unique<Sieve>(); });
}

}  // namespace granuflow::units
