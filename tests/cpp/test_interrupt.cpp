// Stopping runs from outside (granuflow/interrupt.hpp): a poll that asks for a stop ends the run on its thread and the
// runs on other threads with Interrupted at the time each reached, on the DAE and the ODE integrators and in
// steady-state solves; once the scope is gone, the next run is the uninterrupted one to the bit. The polls are counted,
// not timed (interval zero).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "granuflow/interrupt.hpp"
#include "granuflow/simulator.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::scene_from_file;
constexpr auto kEveryCheck = std::chrono::steady_clock::duration::zero();

// The time the run reached when a poll on this thread answered true at its `n`-th call.
double interrupted_at(Scene& s, int n, int& polls) {
  polls = 0;
  InterruptScope scope([&] { return ++polls == n; }, kEveryCheck);
  try {
    simulate(*s.flowsheet, s.options);
  } catch (const Interrupted& e) {
    return e.t();
  }
  return std::nan("");
}

TEST(Interrupt, EndsARunAtTheTimeItReachedAndTheNextRunIsTheWholeOne) {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  const SimResult whole = simulate(*s.flowsheet, s.options);
  int polls = 0;
  EXPECT_EQ(interrupted_at(s, 1, polls), 0.0);  // the first question comes after the set-up, before any step
  EXPECT_EQ(polls, 1);                          // nothing asks again once the flag is set
  const double t_early = interrupted_at(s, 3, polls);
  const double t_late = interrupted_at(s, 6, polls);
  EXPECT_EQ(polls, 6);
  ASSERT_TRUE(std::isfinite(t_early) && std::isfinite(t_late)) << "the run was not interrupted";
  EXPECT_GT(t_early, 0.0);
  EXPECT_LT(t_late, s.options.t_end);
  EXPECT_GT(t_late, t_early);  // later polls, later in the run
  const SimResult again = simulate(*s.flowsheet, s.options);
  EXPECT_FALSE(interrupt_flagged());
  EXPECT_EQ(again.t, whole.t);
  EXPECT_EQ(again.y, whole.y);
  EXPECT_EQ(again.outputs, whole.outputs);
}

TEST(Interrupt, ReachesRunsOnOtherThreads) {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  InterruptScope scope([] { return true; }, kEveryCheck);
  while (!interrupt_requested()) {
  }
  bool stopped = false;
  std::thread worker([&] {  // no scope of its own: it only reads the flag
    try {
      simulate(*s.flowsheet, s.options);
    } catch (const Interrupted& e) {
      stopped = e.t() < s.options.t_end;
    }
  });
  worker.join();
  EXPECT_TRUE(stopped);
}

TEST(Interrupt, StopsTheOdeIntegrators) {
  Scene s = scene_from_file("flowsheets/pbm_constant_kernel.yaml");
  for (Method m : {Method::kBdf, Method::kAdams, Method::kErk}) {
    s.options.method = m;
    int polls = 0;
    const double t = interrupted_at(s, 1, polls);
    EXPECT_TRUE(std::isfinite(t) && t < s.options.t_end) << to_string(m) << ": t = " << t;
  }
}

TEST(Interrupt, StopsASteadyStateSolve) {
  Scene s = scene_from_file("flowsheets/continuous_drying_bed.yaml");  // pseudo-transient steps, then Newton
  const SteadyResult whole = solve_steady_state(*s.flowsheet, SteadyOptions{});
  {
    InterruptScope scope([] { return false; });
    request_interrupt();
    EXPECT_THROW(solve_steady_state(*s.flowsheet, SteadyOptions{}), Interrupted);
  }
  EXPECT_EQ(solve_steady_state(*s.flowsheet, SteadyOptions{}).y, whole.y);
}

TEST(Interrupt, IsNotASolverFailure) {
  // Code that works around a failed solve (a calibration's retries, a sweep's failed points) catches SolverError and
  // must let an interrupt through.
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  InterruptScope scope([] { return true; }, kEveryCheck);
  bool solver_error = false, interrupted = false;
  try {
    simulate(*s.flowsheet, s.options);
  } catch (const SolverError&) {
    solver_error = true;
  } catch (const Interrupted&) {
    interrupted = true;
  }
  EXPECT_FALSE(solver_error);
  EXPECT_TRUE(interrupted);
}

}  // namespace
}  // namespace granuflow
