// State events during a run (events.hpp): the root functions the integrator locates, and what the driver does at a
// root: which events fire, the sensitivity jump (stepper.hpp, SensitivityJump), the parameters they set. The
// flowsheet's parameters and inputs are set back when the run ends, however it ends (a run never changes the
// flowsheet).
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "granuflow/input.hpp"
#include "granuflow/simulator.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

class EventMonitor {
 public:
  EventMonitor(Flowsheet& fs, DaeSystem& sys, const std::vector<EventSpec>& events, const std::vector<int>& sens_ids);
  ~EventMonitor();
  EventMonitor(const EventMonitor&) = delete;
  EventMonitor& operator=(const EventMonitor&) = delete;

  int size() const { return static_cast<int>(events_.size()); }
  std::vector<int> directions() const;
  // g_i = quantity - threshold for an armed event, 1 for one that is not (yet or any more) armed.
  int roots(double t, const double* y, const double* yp, double* g);

  struct Outcome {
    bool fired = false;
    bool stop = false;
    SensitivityJump jump;  // tau empty without sensitivities
  };
  // At a root t located by the integrator (`found`: its root info), with the integrator's values there: the armed
  // events that crossed fire in declaration order (recorded in `log`), their actions are applied.
  Outcome fire(double t, const std::vector<int>& found, const Sample& s, std::vector<EventRecord>& log);
  // For a restart from a checkpoint: the events that had fired (in time order) fire again, without a root.
  void restore(const std::vector<EventRecord>& log);

 private:
  bool armed(size_t i) const;
  void apply(const EventSpec& e);
  std::vector<double> tau(size_t i, double t, const Sample& s);

  Flowsheet& fs_;
  DaeSystem& sys_;
  std::vector<EventSpec> events_;
  std::vector<int> sens_ids_;
  std::vector<int> state_, output_;  // per event: its quantity's index (-1 where the other one applies)
  std::vector<int> fired_;
  std::map<int, double> saved_values_;                                  // parameter id -> value before the run
  std::map<std::string, std::optional<PiecewiseLinear>> saved_inputs_;  // "unit.param" -> its input before the run
  std::vector<double> y_full_, yp_full_, out_, q_zero_;
};

}  // namespace granuflow::detail
