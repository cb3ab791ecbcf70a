// The drying closures a particle hold-up chooses by name (paper 000, sections 5.2, 5.4.1): a normalized drying curve
// (setting drying_curve, registry drying curves) and, where the unit dries from a surface, the surface available for
// drying (setting drying_surface, registry drying surfaces). Their parameters are the unit's own, named
// "drying_<name>" (e.g. bed.drying_gamma), so that calibration stages and --set reach them like any other.
#pragma once
#include <memory>
#include <string>

#include "drying/drying_curve.hpp"
#include "drying/drying_surface.hpp"
#include "granuflow/unit.hpp"

namespace granuflow::kernels {

class DryingClosures {
 public:
  // Declares the settings and parameters; `curve_default` names the default curve, or "" to make the curve optional
  // (setting value "none", the default: the unit keeps its own kinetics). `surfaces`: whether the unit dries from a
  // surface and offers drying_surface.
  void declare(UnitSpec& s, Settings& st, const std::string& curve_default, bool surfaces);
  bool has_curve() const { return curve_ != nullptr; }
  // Whether the curve or the surface changes anything (not the linear curve, not the film).
  bool curve_active() const { return curve_ && !curve_->identity(); }
  bool surface_active() const { return surface_ && !surface_->identity(); }
  std::string curve_name() const { return curve_name_; }
  // What the parameter bounds cannot say (the cubic's A + B + C = 1); ConfigError naming `where`.
  void check(const double* p, const std::string& where) const;
  // v[i] = curve(v[i]) in place, v the normalized moisture capped at 1 on entry; p: the unit's parameters.
  template <class T>
  void curve(const T* p, int n, T* v) const {
    if (curve_active()) curve_->apply(v, n, p + curve_first_, v);
  }
  // area[i] becomes the wetted area of a class holding liquid[i] kg; p: the unit's parameters.
  template <class T>
  void surface(const T* p, const T* liquid, int n, T* area) const {
    if (surface_active()) surface_->apply(area, liquid, n, p + surface_first_, area);
  }

 private:
  std::unique_ptr<DryingCurve> curve_;
  std::unique_ptr<DryingSurface> surface_;
  std::string curve_name_;
  int curve_first_ = 0, surface_first_ = 0;
};

}  // namespace granuflow::kernels
