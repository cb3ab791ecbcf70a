// The surface a class dries from (paper 000, sections 5.2.1-5.2.5): from the class's whole outer surface A_i = N_i pi
// d_i^2 and the liquid it holds (kg), the wetted area the drying flux acts on. The gas-solid heat transfer keeps the
// whole surface; only the evaporation sees the wetted area.
//
// A closure writes once, as a template on the scalar type,
//     template <class T> T wet_area(const T& area, const T& liquid, const T* p) const;
// with p its parameters in the order of params(); the owning unit declares them with a prefix ("drying_").
#pragma once
#include "kernel_base.hpp"

namespace granuflow::kernels {

class DryingSurface : public KernelBase {
 public:
  // wet[i] from area[i] (m^2) and liquid[i] (kg) for n classes; wet and area may be the same array.
  virtual void apply(const double* area, const double* liquid, int n, const double* p, double* wet) const = 0;
  virtual void apply(const Jet* area, const Jet* liquid, int n, const Jet* p, Jet* wet) const = 0;
  // True for the continuous film (wet = area): a unit then applies nothing.
  virtual bool identity() const { return false; }
  ClassNeeds needs() const override {  // the liquid a class holds
    ClassNeeds n;
    n.moisture = true;
    return n;
  }
};

template <class Derived>
class DryingSurfaceT : public DryingSurface {
 public:
  void apply(const double* area, const double* liquid, int n, const double* p, double* wet) const override {
    fill(area, liquid, n, p, wet);
  }
  void apply(const Jet* area, const Jet* liquid, int n, const Jet* p, Jet* wet) const override {
    fill(area, liquid, n, p, wet);
  }

 private:
  template <class T>
  void fill(const T* area, const T* liquid, int n, const T* p, T* wet) const {
    const Derived& d = static_cast<const Derived&>(*this);
    for (int i = 0; i < n; ++i) wet[i] = d.wet_area(area[i], liquid[i], p);
  }
};

}  // namespace granuflow::kernels
