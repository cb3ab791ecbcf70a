// Stream kinds and their fields. A port is a view on the fields of one stream: each field is a state owned by
// exactly one of the two connected units ("provided" by it); the other side reads it in its residual. For
// material streams the outlet provides every field; for heat streams the hot side provides T and the unit
// that computes the flow provides Q. No copy equations, no tear streams.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

enum class StreamKind { Gas, Liquid, Solids, Heat, Vapour, Holdup, Wetting };
// Out and In ports join exactly one peer. A Probe is an outlet whose fields are all provided by its unit and
// which carries no material: any number of In ports may read it (a unit exposing its state to closures).
enum class PortDir { In, Out, Probe };

std::string to_string(StreamKind k);
StreamKind stream_kind_from_string(const std::string& s);
std::string to_string(PortDir d);

struct FieldSpec {
  std::string name;
  std::string unit;
};

// Field layout of a stream. Solids carry `classes` per-class dry-solid mass flows, then `classes` moistures,
// then one temperature. Vapour: water-vapour mass flow and its temperature. Holdup (a bed's state, read through
// a probe): `classes` dry-solid masses, `classes` water masses, bed temperature, superficial gas velocity.
// Per-class streams carry the pivot diameters of their grid as port metadata, checked equal on connection.
// Wetting (spray zone -> bed, per class): deposited liquid flows, wetted surface fractions, wet-spot moistures,
// then the liquid temperature.
std::vector<FieldSpec> stream_fields(StreamKind kind, int classes);

namespace gas {  // dry-gas mass flow, absolute humidity (kg water / kg dry gas), temperature, pressure
enum Field { kMdot = 0, kY = 1, kT = 2, kP = 3 };
}
namespace liquid {  // mass flow, temperature, dissolved-solids mass fraction
enum Field { kMdot = 0, kT = 1, kW = 2 };
}
namespace heat {  // heat flow from the Out side to the In side, temperature of the providing side
enum Field { kQ = 0, kT = 1 };
}
namespace vapour {
enum Field { kMdot = 0, kT = 1 };
}
namespace holdup {
inline int mass(int i) { return i; }
inline int water(int classes, int i) { return classes + i; }
inline int T(int classes) { return 2 * classes; }
inline int u0(int classes) { return 2 * classes + 1; }
// kg: a class's moisture is W / (M + kMassFloor), finite for an emptied class; every reader of a holdup uses it
inline constexpr double kMassFloor = 1e-12;
}  // namespace holdup
namespace wetting {
inline int mdot(int i) { return i; }
inline int fwet(int classes, int i) { return classes + i; }
inline int Xwet(int classes, int i) { return 2 * classes + i; }
inline int T(int classes) { return 3 * classes; }
}  // namespace wetting
namespace solids {
inline int mdot(int i) { return i; }
inline int X(int classes, int i) { return classes + i; }
inline int T(int classes) { return 2 * classes; }
}  // namespace solids

}  // namespace granuflow
