// Signals between units outside the streams: a controller measures a state or an output of one unit and sets a
// parameter of another. A parameter set this way is "driven": in every evaluation of the equations (residual,
// Jacobian, sensitivities, outputs) it takes the value of its source, and the Jacobian of the unit that reads it
// gains the source's columns (one state, or every column the source unit's outputs read), so Jacobians and
// sensitivities stay exact. A driven parameter cannot be set, given an input or take part in a link: its value
// would never be used.
//
// A unit asks for signals by implementing SignalUnit besides Unit (its wiring fixed in declare() from its settings);
// the flowsheet resolves and checks them when it is finalized (resolve_drives) and every DaeSystem applies them.
#pragma once
#include <string>
#include <vector>

#include "granuflow/unit.hpp"

namespace granuflow {

class Flowsheet;

class SignalUnit {
 public:
  virtual ~SignalUnit() = default;
  // Own parameter `param` takes the value of `source`, a state or reported output of another unit ("gas.T").
  struct Read {
    ParamId param;
    std::string source;
    std::string setting;  // the setting that named the source, for messages
  };
  // Parameter `target` of another unit ("inlet.T") takes the value of own state `state`.
  struct Write {
    StateId state;
    std::string target;
    std::string setting;
  };
  virtual std::vector<Read> reads() const = 0;
  virtual std::vector<Write> writes() const = 0;
};

// A unit that holds one of its outputs at one of its parameters (a controller, or a unit with an ideal controller
// inside): a steady state says when it misses it (steady_state.cpp).
class HoldsSetPoint {
 public:
  virtual ~HoldsSetPoint() = default;
  struct SetPoint {
    ParamId set_point;
    OutputId value;
  };
  virtual std::vector<SetPoint> set_points() const = 0;
};

// A drive of a finalized flowsheet: parameter `param` of unit `unit` takes the value of global state `state`, or of
// output `output` of unit `source_unit`.
struct Drive {
  int unit = -1, param = -1;
  int state = -1;
  int source_unit = -1, output = -1;
  std::string label;  // "inlet.T <- tic.u (setting tic.drive)"
};

// Every drive of a finalized flowsheet, resolved and checked: a ConfigError naming the setting for an unknown or
// missing name, a parameter driven twice or also given an input or a link, a parameter of a particle system, a
// source that is an integrated quantity (quadrature), an explicit unit driven by an output or a unit reading an
// output of a unit that is itself driven by an output.
std::vector<Drive> resolve_drives(const Flowsheet& fs);

// What drives global parameter `id`, as "tic.u (setting tic.drive)", or "" when nothing does (works before finalize).
std::string driven_by(const Flowsheet& fs, int id);

// One line per set point a unit misses (HoldsSetPoint) at time t, given every output (Flowsheet::output_names order):
// "unit gran (granulator) misses its set point: gran.mass = 83.2 kg, set point gran.M_set = 100 kg (...)".
std::vector<std::string> missed_set_points(const Flowsheet& fs, double t, const std::vector<double>& outputs);

}  // namespace granuflow
