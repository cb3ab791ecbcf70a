// Stopping a run from outside it: Ctrl-C in Python, or a notebook's "interrupt kernel".
// A caller installs a poll on its thread (InterruptScope); the integrators' callbacks and the run driver ask
// interrupt_requested() between steps. A poll that answers true sets one process-wide flag, so runs on the caller's
// worker threads (a calibration's experiments, a sweep's points) stop as well; each run then ends with Interrupted.
// Nothing here touches the numbers: a run that is not interrupted is the same, bit for bit.
#pragma once
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "granuflow/errors.hpp"

namespace granuflow {

// A run stopped at the caller's request. Not a SolverError: nothing failed, and code that retries or works around a
// failed solve (calibration, sweeps, the grid check) must let it through.
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(double t) : std::runtime_error("interrupted at t = " + fmt_num(t) + " s"), t_(t) {}
  // Work made of many runs (a calibration): where it stopped, in its own words; t() is then NaN.
  explicit Interrupted(const std::string& where) : std::runtime_error(where), t_(std::nan("")) {}
  double t() const { return t_; }  // the time the run had reached

 private:
  double t_;
};

// True once a poll asked for a stop, for as long as any InterruptScope lives. On a thread with a scope, asks
// its poll once an interval has passed (reading the clock).
bool interrupt_requested();

// The flag alone, without polling (after a failed solve: was it the interrupt?).
bool interrupt_flagged();

// For the integrators' callbacks, run thousands of times a second: the flag at every call, and the clock and poll at
// every 16th (counted in `calls`, the caller's).
inline bool interrupt_requested(unsigned& calls) {
  return (++calls & 15u) == 0 ? interrupt_requested() : interrupt_flagged();
}

// Runs `solve` (a simulation, a steady-state solve) and turns the SolverError it ends with when a callback refused to
// go on because of the interrupt into Interrupted: nothing failed.
template <class F>
auto interruptible(F&& solve) {
  try {
    return solve();
  } catch (const SolverError& e) {
    if (interrupt_flagged()) throw Interrupted(e.t());
    throw;
  }
}

// Sets the flag: for a caller that learned of the interrupt itself (a progress callback that raised it). Only while
// a scope lives (none would clear it).
void request_interrupt();

// Installs `poll` on this thread for the scope's lifetime. The flag is cleared when the first scope on any thread
// begins and when the last one ends: an interrupt ends the runs of its time, not the next ones. The poll is never
// asked before one interval has passed, so a short run never calls it.
class InterruptScope {
 public:
  static constexpr std::chrono::milliseconds kPollInterval{100};
  explicit InterruptScope(std::function<bool()> poll, std::chrono::steady_clock::duration interval = kPollInterval);
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  bool due();  // called by interrupt_requested(): the poll's answer when an interval has passed, else false

 private:
  std::function<bool()> poll_;
  InterruptScope* outer_;
  std::chrono::steady_clock::duration interval_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace granuflow
