// Stream kinds and their fields. A port is a view on the fields of one stream: each field is a state owned by
// exactly one of the two connected units ("provided" by it); the other side reads it in its residual. For
// material streams the outlet provides every field; for heat streams the hot side provides T and the unit
// that computes the flow provides Q. No copy equations, no tear streams.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

enum class StreamKind { Gas, Liquid, Solids, Heat };
enum class PortDir { In, Out };

std::string to_string(StreamKind k);
StreamKind stream_kind_from_string(const std::string& s);
std::string to_string(PortDir d);

struct FieldSpec {
  std::string name;
  std::string unit;
};

// Field layout of a stream. Solids carry `classes` per-class dry-solid mass flows, then `classes` moistures,
// then one temperature.
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
namespace solids {
inline int mdot(int i) { return i; }
inline int X(int classes, int i) { return classes + i; }
inline int T(int classes) { return 2 * classes; }
}  // namespace solids

}  // namespace granuflow
