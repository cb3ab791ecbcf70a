// The stream kinds of paper 001's spray-zone/bed coupling, defined with the units that use them (the framework's
// generic kinds are in framework/include/granuflow/stream.hpp):
//   * holdup (a bed's state read through its probe port): per class dry-solid mass, per class water mass, the bed
//     temperature and the superficial gas velocity;
//   * wetting (spray zone -> bed, per class): deposited liquid flow, wetted surface fraction (Eq. (41)), wet-spot
//     moisture (Eq. (55)), then the liquid temperature, the deposited liquid's dissolved-solids fraction and, at the
//     n + 1 cell faces, Eq. (29)'s residence-time fraction (the shape of the binder's layering growth).
#pragma once
#include "granuflow/stream.hpp"
#include "particles.hpp"

namespace granuflow::units::paper001 {

StreamKind holdup_stream();
StreamKind wetting_stream();

namespace holdup {
using holdup_layout::mass, holdup_layout::water, holdup_layout::T;
inline int u0(int classes) { return holdup_layout::last(classes); }
}  // namespace holdup
namespace wetting {
inline int mdot(int i) { return i; }
inline int fwet(int classes, int i) { return classes + i; }
inline int Xwet(int classes, int i) { return 2 * classes + i; }
inline int T(int classes) { return 3 * classes; }
inline int w(int classes) { return 3 * classes + 1; }
inline int tau_face(int classes, int f) { return 3 * classes + 2 + f; }  // f = 0 .. classes
}  // namespace wetting

}  // namespace granuflow::units::paper001
