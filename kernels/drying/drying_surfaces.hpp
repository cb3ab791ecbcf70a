// The surfaces available for drying of paper 000, sections 5.2.1-5.2.5 (drying_surface.hpp gives the contract):
//  * film (5.2.1): a continuous liquid film over the whole outer surface of the volume-equivalent sphere, A_wet = A
//    (paper 001, Eq. (70));
//  * correction (5.2.2): the outer surface times a fitted factor, A_wet = f A;
//  * coverage (5.2.3): the liquid held as droplets of the spray's diameter d_d, each covering its projected area
//    pi d_d^2 / 4 (Kariuki's coating number phi = n_d A_d / A, in the accessible-droplet form n_d A_d / (n_p A_p) of
//    Hussain et al.), randomly placed so that they overlap: A_wet = A (1 - exp(-phi)) (paper 001, Eq. (41));
//  * droplet_height (5.2.4): the liquid held as sessile spherical caps of the droplet's volume at the contact angle
//    theta (paper 003, Eqs. (7.53), (7.54): base radius a, height h), their footprints placed at random over the
//    surface, and the gas-liquid interface of a cap pi (a^2 + h^2) drying: A_wet = A (1 - exp(-n_d pi a^2 / A))
//    (1 + (h / a)^2). A cap dries by losing height (Eq. (7.55)); here a class holds whole caps of the sprayed size
//    (its liquid over one droplet's volume), not a count of shrinking ones, which would need a droplet state per class.
// The balance-equation film of section 5.2.5 (film thickness by Weber and Reynolds numbers) needs the impact of each
// droplet and is not a closure of this kind.
#pragma once
#include <cmath>
#include <vector>

#include "drying/drying_surface.hpp"
#include "granuflow/registry.hpp"
#include "particle_geometry.hpp"

namespace granuflow::kernels {

// Keeps an emptied class (A = 0, no liquid) at zero wetted area instead of 0 / 0.
inline constexpr double kAreaFloor = 1e-30;  // m^2

class FilmSurface : public DryingSurfaceT<FilmSurface> {
 public:
  bool identity() const override { return true; }
  template <class T>
  T wet_area(const T& area, const T&, const T*) const {
    return area;  // paper 000, section 5.2.1: the whole outer surface
  }
};

class CorrectedSurface : public DryingSurfaceT<CorrectedSurface> {
 public:
  std::vector<ParamSpec> params() const override;
  template <class T>
  T wet_area(const T& area, const T&, const T* p) const {
    return p[0] * area;  // paper 000, section 5.2.2: a fitted correction factor of the outer surface
  }
};

// Kariuki's coating number of a class from its liquid volume (paper 000, section 5.2.3): n_d pi d_d^2 / 4 over A with
// n_d = V_l / (pi d_d^3 / 6), i.e. 3 V_l / (2 d_d A).
template <class T>
T coating_number_of_liquid(const T& v_liquid, const T& area, const T& d_drop) {
  return 1.5 * v_liquid / (d_drop * (area + kAreaFloor));
}

class CoverageSurface : public DryingSurfaceT<CoverageSurface> {
 public:
  std::vector<ParamSpec> params() const override;
  template <class T>
  T wet_area(const T& area, const T& liquid, const T* p) const {
    using std::expm1;
    // paper 000, section 5.2.3 (Kariuki coating number); paper 001, Eq. (41): covered fraction 1 - exp(-phi)
    return -area * expm1(-coating_number_of_liquid(T(liquid / p[1]), area, p[0]));
  }
};

// Paper 003, Eq. (7.53): base radius of a spherical cap of volume v at contact angle theta (rad).
template <class T>
T cap_base_radius(const T& v, const T& theta) {
  using std::cbrt, std::cos, std::sin;
  const T c = cos(theta), s = sin(theta);
  return cbrt(3.0 * v / kPi * s * s * s / (2.0 - 3.0 * c + c * c * c));
}

// Paper 003, Eq. (7.54): h / a = (1 - cos theta) / sin theta of a spherical cap.
template <class T>
T cap_aspect(const T& theta) {
  using std::cos, std::sin;
  return (1.0 - cos(theta)) / sin(theta);
}

class DropletHeightSurface : public DryingSurfaceT<DropletHeightSurface> {
 public:
  std::vector<ParamSpec> params() const override;
  template <class T>
  T wet_area(const T& area, const T& liquid, const T* p) const {
    using std::expm1;
    const T& d = p[0];
    const T v_drop = sphere_volume(d);
    const T a = cap_base_radius(v_drop, p[2]);                                // paper 003, Eq. (7.53)
    const T k = cap_aspect(p[2]);                                             // paper 003, Eq. (7.54)
    const T footprints = liquid / (p[1] * v_drop) * kPi * a * a;              // n_d pi a^2
    return -area * expm1(-footprints / (area + kAreaFloor)) * (1.0 + k * k);  // paper 000, section 5.2.4
  }
};

void register_drying_surfaces(Registry<DryingSurface>& r);

}  // namespace granuflow::kernels
