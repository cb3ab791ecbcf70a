// Stream kinds and their fields. A port is a view on the fields of one stream: each field is a state owned by
// exactly one of the two connected units ("provided" by it), or passed on unchanged from one of the unit's inlets
// (forwarded); the other side reads it in its residual. For material streams the outlet provides every field; for
// heat streams the hot side provides T and the unit that computes the flow provides Q. No copy equations, no tear
// streams.
//
// The framework defines the generic kinds below; a unit library defines its own (a model-specific coupling such
// as paper 001's spray zone -> bed wetting, a 2-D distribution) with a StreamType of its own, without touching the
// framework: kinds are compared by identity, so each must be defined once (a function-local static).
#pragma once
#include <string>
#include <vector>

namespace granuflow {

struct FieldSpec {
  std::string name;
  std::string unit;
};

struct StreamType {
  std::string name;
  std::string description;
  std::vector<FieldSpec> (*fields)(int classes);  // field layout for a stream with `classes` size classes
};
using StreamKind = const StreamType*;

// Out and In ports join exactly one peer. A Probe is an outlet whose fields are all provided by its unit and
// which carries no material: any number of In ports may read it (a unit exposing its state to closures).
enum class PortDir { In, Out, Probe };

inline std::string to_string(StreamKind k) { return k ? k->name : "?"; }
std::string to_string(PortDir d);
inline std::vector<FieldSpec> stream_fields(StreamKind kind, int classes) { return kind->fields(classes); }
// name_0 .. name_{n-1} with one unit: the per-class part of a layout.
void append_class_fields(std::vector<FieldSpec>& f, const std::string& name, int classes, const std::string& unit);

namespace streams {
StreamKind gas();     // dry-gas mass flow, absolute humidity (kg water / kg dry gas), temperature, pressure
StreamKind liquid();  // mass flow, temperature, dissolved-solids mass fraction
StreamKind heat();    // heat flow from the Out side to the In side, temperature of the providing side
StreamKind vapour();  // water-vapour mass flow and its temperature
StreamKind solids();  // per class dry-solid mass flows, per class water mass flows, temperature
// Solids of a particle system with `components` named solids (particles.hpp): the fields of solids(), then per
// component after the first its per-class mass flows (the first's is mdot_i minus the others). solids(1) is solids().
inline constexpr int kMaxComponents = 4;
StreamKind solids(int components);
}  // namespace streams

namespace gas {
enum Field { kMdot = 0, kY = 1, kT = 2, kP = 3 };
}
namespace liquid {
enum Field { kMdot = 0, kT = 1, kW = 2 };
}
namespace heat {
enum Field { kQ = 0, kT = 1 };
}
namespace vapour {
enum Field { kMdot = 0, kT = 1 };
}
namespace solids {
inline int mdot(int i) { return i; }
inline int water(int classes, int i) { return classes + i; }
inline int T(int classes) { return 2 * classes; }
// Mass flow of component c >= 1 in class i (streams::solids(components)).
inline int component(int classes, int c, int i) { return 2 * classes + 1 + (c - 1) * classes + i; }
}  // namespace solids

// kg: a class's moisture is W / (M + kMassFloor), finite for an emptied class; every reader of a class inventory
// uses it.
inline constexpr double kMassFloor = 1e-12;

}  // namespace granuflow
