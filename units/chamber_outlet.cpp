#include "chamber_outlet.hpp"

#include <string>
#include <utility>
#include <vector>

#include "classifier.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow::units {

StreamKind chamber_holdup() {
  static const StreamType t{"chamber hold-up",
                            "a chamber's state for its outlet: per class dry solids and water, T, rate", [](int n) {
                              return holdup_field_specs(n, {"rate", "1/s"});
                            }};
  return &t;
}

namespace {
template <int K>
StreamKind holdup_of() {
  static const StreamType t{"chamber hold-up/" + std::to_string(K) + " components",
                            "a chamber's state for its outlet: per class dry solids and water, T, rate, per class "
                            "mass of the components after the first",
                            [](int n) {
                              std::vector<FieldSpec> f = holdup_field_specs(n, {"rate", "1/s"});
                              for (int c = 1; c < K; ++c) append_class_fields(f, "comp" + std::to_string(c), n, "kg");
                              return f;
                            }};
  return &t;
}
}  // namespace

StreamKind chamber_holdup(int components) {
  switch (components) {
    case 2:
      return holdup_of<2>();
    case 3:
      return holdup_of<3>();
    case 4:
      return holdup_of<4>();
    default:
      return chamber_holdup();
  }
}

namespace {

struct Work : Workspace {
  Classifier::Cache cls;
  std::vector<double> hd;  // the hold-up gathered where its fields are not consecutive (Ctx::port_array)
  std::vector<Jet> hj;
};

class ChamberOutlet : public UnitBase<ChamberOutlet> {
 public:
  ChamberOutlet(std::string owner, ChamberOutletSpec spec) : owner_(std::move(owner)), spec_(std::move(spec)) {}
  std::string type() const override { return "chamber_outlet"; }
  void declare(UnitSpec& s, Settings&) override {
    const int n = spec_.classes;
    if (spec_.classifier) s.use_shared_params(owner_);  // the separation curve's parameters are the owner's
    sM_ = s.add_states("mdot", n, StateKind::Algebraic, "kg/s", 1e-2);
    if (spec_.wet) sW_ = s.add_states("water", n, StateKind::Algebraic, "kg/s", 1e-3);
    for (int k = 1; k < spec_.components; ++k)
      sQ_.push_back(s.add_states("comp" + std::to_string(k), n, StateKind::Algebraic, "kg/s", 1e-2));
    in_ = s.add_port("in", chamber_holdup(spec_.components), PortDir::In, n);
    s.set_port_grid(in_, spec_.diameters);
    const PortId out = s.add_port("out", streams::solids(spec_.components), PortDir::Out, n);
    s.set_port_grid(out, spec_.diameters);
    for (int i = 0; i < n; ++i) {
      s.provide(out, solids::mdot(i), sM_ + i);
      if (spec_.wet)
        s.provide(out, solids::water(n, i), sW_ + i);
      else
        s.forward(out, solids::water(n, i), in_, holdup_fields::water(n, i));  // the dry chamber's zero
    }
    s.forward(out, solids::T(n), in_, holdup_fields::T(n));
    for (int k = 1; k < spec_.components; ++k)
      for (int i = 0; i < n; ++i) s.provide(out, solids::component(n, k, i), sQ_[k - 1] + i);
    s.set_explicit();
    ClassLayout layout{n, {sM_}, {{in_, holdup_fields::mass(0)}}};
    if (spec_.wet) layout.state_blocks.push_back(sW_), layout.field_blocks.push_back({in_, holdup_fields::water(n, 0)});
    for (int k = 1; k < spec_.components; ++k)
      layout.state_blocks.push_back(sQ_[k - 1]),
          layout.field_blocks.push_back({in_, holdup_fields::component(n, k, 0)});
    s.set_classes(layout);
  }
  std::unique_ptr<Workspace> workspace() const override { return std::make_unique<Work>(); }

  template <class T>
  Status eval(const Ctx<T>& c) const {
    const int n = spec_.classes;
    const T* frac = spec_.classifier ? spec_.classifier->fractions(c.shared, c.template ws<Work>().cls) : nullptr;
    const T& r = c.port(in_, holdup_fields::rate(n));
    auto& scratch = per_scalar<T>(c.template ws<Work>().hd, c.template ws<Work>().hj);
    flows(n, r, frac, c.port_array(in_, holdup_fields::mass(0), n, scratch), &c.x(sM_), &c.res(sM_));
    if (spec_.wet) flows(n, r, frac, c.port_array(in_, holdup_fields::water(n, 0), n, scratch), &c.x(sW_), &c.res(sW_));
    for (int k = 1; k < spec_.components; ++k)
      flows(n, r, frac, c.port_array(in_, holdup_fields::component(n, k, 0), n, scratch), &c.x(sQ_[k - 1]),
            &c.res(sQ_[k - 1]));
    return Status::kOk;
  }
  // res_i = x_i - r f_i h_i (f_i = 1 without a classifier) for the flows of one field.
  template <class T>
  static void flows(int n, const T& r, const T* frac, const T* h, const T* x, T* res) {
    outlet_flows(n, r, frac, h, res);
    for (int i = 0; i < n; ++i) res[i] = x[i] - res[i];
  }
  template <class T>
  void init(InitCtx<T>& c) const {  // evaluated inline; these only fill a run without inlining's first guess
    for (int i = 0; i < spec_.classes; ++i) {
      c.x(sM_ + i) = T(0.0);
      if (spec_.wet) c.x(sW_ + i) = T(0.0);
      for (StateId q : sQ_) c.x(q + i) = T(0.0);
    }
  }

 private:
  std::string owner_;
  ChamberOutletSpec spec_;
  StateId sM_, sW_;
  std::vector<StateId> sQ_;
  PortId in_;
};

}  // namespace

std::unique_ptr<Unit> make_chamber_outlet(const std::string& owner, ChamberOutletSpec spec) {
  return std::make_unique<ChamberOutlet>(owner, std::move(spec));
}

}  // namespace granuflow::units
