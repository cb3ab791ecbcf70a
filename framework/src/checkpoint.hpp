// Checkpoint files (docs/events_and_checkpoints.md): the full state of a run at a checkpoint time, so that a later
// run restarts there bit-identically. IDAS's history (its step size, order and back values) cannot be saved through
// its API, so a checkpoint time is a breakpoint of every run that names it: the run stops there and restarts its
// integrator from the values it reached, and a restart from the file does exactly that. The file holds what the
// next segment starts from (the integrator's unknowns, derivatives, quadratures and sensitivities), the results
// recorded so far and the events that fired; doubles are stored as their bytes, so nothing is rounded.
#pragma once
#include <string>
#include <vector>

#include "granuflow/simulator.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

struct Checkpoint {
  std::string scene, structure;  // the flowsheet's name, and its states, outputs, quadratures and sensitivities
  long states = 0;
  size_t segment = 0;      // index of the segment that starts at state.t
  size_t next_output = 0;  // index of the first output time not yet recorded
  StepperState state;
  SimResult partial;  // t, y, yp, outputs, sens, output_sens and events up to state.t
};

// What a checkpoint must match to be restarted: the structure of the flowsheet and the sensitivities of the run.
std::string structure_signature(const Flowsheet& fs, const SimOptions& opt);
// checkpoint_<t>s.gfckpt in `dir`.
std::string checkpoint_path(const std::string& dir, double t);
void write_checkpoint(const std::string& path, const Checkpoint& c);
// Refuses with one ConfigError line a file that is no checkpoint, or one another scene or structure wrote.
Checkpoint read_checkpoint(const std::string& path, const Flowsheet& fs, const SimOptions& opt);

}  // namespace granuflow::detail
