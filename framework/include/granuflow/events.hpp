// State events of a recipe (scene key `events`, docs/events_and_checkpoints.md): a condition on a state or a reported
// output, located by the integrator's root finding, and what happens there (parameters set, an input switched to a
// constant, the run stopped). Checkpoints (scene key `checkpoints`): times at which a run stops, writes its full
// state and restarts, so that a later run can resume from the file bit-identically.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

struct EventAction {
  std::string target;  // "unit.param"
  double value = 0.0;  // SI
  std::string text;    // as written, for messages and results
};

struct EventSpec {
  std::string name;
  std::string when;      // the condition as written, e.g. "bed.d50 >= 450 um"
  std::string quantity;  // "unit.state" or "unit.output"
  double threshold = 0;  // SI
  int direction = 1;     // +1: fires when the quantity rises through the threshold (>, >=); -1: falls (<, <=)
  bool repeat = false;   // false: fires once
  std::string after;     // armed only once the event of this name has fired ("": from the start)
  std::string phase;     // name of the recipe phase it begins ("": the event's name)
  std::vector<EventAction> set;
  bool stop = false;
};

// One event that fired, in SimResult::events.
struct EventRecord {
  std::string name;
  std::string phase;
  double t = 0.0;  // s
};

}  // namespace granuflow
