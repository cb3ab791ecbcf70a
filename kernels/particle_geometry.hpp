// Sphere geometry shared by the transfer, drying and spray-zone closures (paper 001 treats particles and
// droplets as ideal spheres).
#pragma once

namespace granuflow::kernels {

inline constexpr double kPi = 3.14159265358979323846;

// Eq. (51), paper 001.
template <class T>
T sphere_surface(const T& d) {
  return kPi * d * d;
}

template <class T>
T sphere_volume(const T& d) {
  return kPi / 6.0 * d * d * d;
}

// Total surface of n equal spheres: the area of a size class in Eq. (70) and in A_p of Eqs. (74), (87)
// (docs/paper001_decisions.md).
template <class T>
T class_surface(const T& n, const T& d) {
  return n * sphere_surface(d);
}

// Eq. (50), paper 001: the droplet touches the particle with its cross-section.
template <class T>
T sphere_cross_section(const T& d) {
  return 0.25 * kPi * d * d;
}

}  // namespace granuflow::kernels
