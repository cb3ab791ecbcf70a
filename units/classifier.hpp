// A separation curve (kernels/classification) as a unit uses it: chosen by a setting, its parameters declared in the
// unit under a prefix ("upper_d_cut", "class_m"), and evaluated as one fraction per size class (the cell averages of
// the curve, separation_curve.hpp). The fractions depend on parameters only: cached per run for doubles, and
// recomputed in Jets only when one of the curve's parameters carries a derivative (a sensitivity).
#pragma once
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/discretization/grid.hpp"
#include "kernels/registry.hpp"

namespace granuflow::units {

class Classifier {
 public:
  // Reads the setting `setting` (a curve name, default `def`) and declares the curve's parameters as `prefix` + name,
  // the cut size with the default `d_cut_default` (m).
  void declare(UnitSpec& s, Settings& st, const std::string& setting, const std::string& def, const std::string& prefix,
               const std::string& description, std::shared_ptr<const kernels::Grid> grid, double d_cut_default) {
    const auto& reg = kernels::registries().separation;
    name_ = st.get_choice(setting, def, reg.names(), description);
    curve_ = reg.create(name_, st.where());
    curve_->declare(st, prefix);
    grid_ = std::move(grid);
    first_ = static_cast<int>(s.params().size());
    for (ParamSpec p : curve_->params()) {
      if (p.name == "d_cut") d_cut_ = static_cast<int>(s.params().size()), p.value = d_cut_default;
      p.name = prefix + p.name;
      s.add_param(std::move(p));
    }
    count_ = static_cast<int>(s.params().size()) - first_;
  }
  int size() const { return grid_->size(); }
  // The cut size's parameter index in the unit (every curve has one).
  int d_cut_index() const { return d_cut_; }
  const std::string& name() const { return name_; }

  // Fractions to the coarse side per class, for the unit's parameters `p` (doubles or Jets); `cache` holds the
  // doubles of the last parameter values seen and the Jets' work array (a unit keeps one per curve in its workspace).
  struct Cache {
    std::vector<double> key, value;
    std::vector<Jet> jets, scratch;
  };
  template <class T>
  const T* fractions(const T* p, Cache& c) const {
    if constexpr (std::is_same_v<T, double>) {
      refresh(p, c);
      return c.value.data();
    } else {
      return jet_fractions(p, c);
    }
  }

 private:
  const Jet* jet_fractions(const Jet* p, Cache& c) const {
    bool derivative = false;
    for (int k = first_; k < first_ + count_; ++k) derivative = derivative || !p[k].v.isZero();
    if (derivative) {
      const auto& de = grid_->diameter_edges();
      c.scratch.resize(size());
      for (int i = 0; i < size(); ++i) c.scratch[i] = curve_->cell_fraction(de[i], de[i + 1], p + first_);
      return c.scratch.data();
    }
    std::vector<double> v(count_);
    for (int k = 0; k < count_; ++k) v[k] = p[first_ + k].a;
    if (c.key != v) {
      std::vector<double> full(first_ + count_);
      for (int k = 0; k < count_; ++k) full[first_ + k] = v[k];
      refresh(full.data(), c);
    }
    return c.jets.data();
  }

  void refresh(const double* p, Cache& c) const {
    if (!c.value.empty() && std::equal(c.key.begin(), c.key.end(), p + first_)) return;
    c.key.assign(p + first_, p + first_ + count_);
    const auto& de = grid_->diameter_edges();
    c.value.resize(size());
    c.jets.resize(size());
    for (int i = 0; i < size(); ++i) {
      c.value[i] = curve_->cell_fraction(de[i], de[i + 1], p + first_);
      c.jets[i] = Jet(c.value[i]);
    }
  }

  std::string name_;
  std::unique_ptr<kernels::SeparationCurve> curve_;
  std::shared_ptr<const kernels::Grid> grid_;
  int first_ = 0, count_ = 0, d_cut_ = -1;
};

}  // namespace granuflow::units
