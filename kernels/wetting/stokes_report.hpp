// The Stokes deformation number of paper 000, section 5.6, as a reported result of a bed (setting
// stokes_deformation: off | report): the viscous Stokes number of a collision of two granules of the bed's mass median
// diameter d50 (paper 003, Eq. (7.57); masses rho_p pi d50^3 / 6, the partners' harmonic means equal to one granule)
// against the critical numbers of coalescence (Eq. (7.58)) and deformation, St*_def = 2 St*_coal (paper 000,
// section 5.6). The regime output names the outcome: 0 the granules coalesce (St < St*_coal), 1 they rebound intact
// (St*_coal <= St < St*_def), 2 they deform or break (St >= St*_def).
#pragma once
#include "granuflow/unit.hpp"
#include "particle_geometry.hpp"
#include "wetting/stokes_deformation.hpp"

namespace granuflow::kernels {

class StokesReport {
 public:
  // Declares the setting and, for `report`, the parameters stokes_u_coll, _mu_l, _h, _h_a, _e and the outputs.
  void declare(UnitSpec& s, Settings& st);
  bool active() const { return active_; }

  template <class T, class C>
  void outputs(const C& c, const T& d50, const T& rho_p) const {
    if (!active_) return;
    const T* p = &c.par(first_);
    const T mass = rho_p * kPi / 6.0 * d50 * d50 * d50;
    const T st = stokes::viscous_stokes_number(mass, p[0], p[1], d50);  // paper 003, Eq. (7.57)
    const T coal = stokes::critical_coalescence(p[4], p[2], p[3]);      // paper 003, Eq. (7.58)
    const T def = stokes::critical_deformation(p[4], p[2], p[3]);       // paper 000, section 5.6
    c.out(o_st_) = st, c.out(o_coal_) = coal, c.out(o_def_) = def;
    c.out(o_regime_) = T(st < coal ? 0.0 : st < def ? 1.0 : 2.0);
  }

 private:
  bool active_ = false;
  ParamId first_;
  OutputId o_st_, o_coal_, o_def_, o_regime_;
};

}  // namespace granuflow::kernels
