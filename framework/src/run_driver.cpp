#include "run_driver.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "checkpoint.hpp"
#include "events_run.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "run_common.hpp"

namespace granuflow::detail {

void throw_step_failure(const Flowsheet& fs, DaeSystem& sys, const StepFailure& f) {
  const int n = sys.size();
  std::string where = "unknown unit", uname = "?";
  double worst = 0;
  try {
    std::vector<double> r(n);
    sys.residual(f.t, f.y, f.yp, r.data());
    int iw = 0;
    for (int i = 0; i < n; ++i) {
      const double v = std::isfinite(r[i]) ? std::abs(r[i] * f.weights[i]) : HUGE_VAL;
      if (v > worst) worst = v, iw = i;
    }
    where = sys.describe_row(iw);
    uname = fs.units()[fs.state_unit(iw)].name;
  } catch (...) {  // a residual that throws at the failed state: the flag and the callback's error say the rest
  }
  std::ostringstream os;
  os << f.what << " failed at t = " << f.t << " s in " << where << ": " << f.flag_text << "; worst weighted residual "
     << worst;
  throw SolverError(os.str(), f.t, uname, worst);
}

namespace {

// The segments' ends: the inputs' breakpoints and the checkpoint times, then t_end.
std::vector<double> segment_ends(const Flowsheet& fs, const SimOptions& opt) {
  std::vector<double> ends = fs.breakpoints(opt.t_end);
  if (!opt.checkpoints.empty()) {
    ends.insert(ends.end(), opt.checkpoints.begin(), opt.checkpoints.end());
    std::sort(ends.begin(), ends.end());
    ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  }
  ends.push_back(opt.t_end);
  return ends;
}

bool is_checkpoint(const SimOptions& opt, double t) {
  return std::find(opt.checkpoints.begin(), opt.checkpoints.end(), t) != opt.checkpoints.end();
}

std::string save_checkpoint(const SimOptions& opt, const Flowsheet& fs, Stepper& stepper, const EventMonitor& events,
                            const SimResult& res, double t, size_t seg, size_t iout) {
  Checkpoint c;
  c.settings = events.switched_settings();
  c.scene = fs.name(), c.structure = structure_signature(fs, opt), c.states = fs.n_states();
  c.segment = seg, c.next_output = iout;
  stepper.save(c.state);
  c.state.t = t;
  c.partial.t = res.t, c.partial.y = res.y, c.partial.yp = res.yp, c.partial.outputs = res.outputs;
  c.partial.sens = res.sens, c.partial.output_sens = res.output_sens, c.partial.events = res.events;
  const std::string path = checkpoint_path(opt.checkpoint_dir, t);
  write_checkpoint(path, c);
  return path;
}

// A run that resumes from a checkpoint: the results and events up to it, the integrator's values there.
void restart(const SimOptions& opt, const Flowsheet& fs, const DaeSystem& sys, Stepper& stepper, EventMonitor& events,
             SimResult& res, double& t0, size_t& seg, size_t& iout) {
  Checkpoint c = read_checkpoint(opt.restart_file, fs, opt);
  if (c.state.y.size() != size_t(sys.size()))
    throw ConfigError("restart " + opt.restart_file + ": written with " + std::to_string(c.state.y.size()) +
                      " unknowns, this run has " + std::to_string(sys.size()) +
                      " (another linear solver inlines other units): restart with the writing run's solver options");
  res.t = std::move(c.partial.t), res.y = std::move(c.partial.y), res.yp = std::move(c.partial.yp);
  res.outputs = std::move(c.partial.outputs), res.sens = std::move(c.partial.sens);
  res.output_sens = std::move(c.partial.output_sens), res.events = c.partial.events;
  events.restore(c.partial.events);
  // The settings the writing run's events had switched are those this run's events switch again (the same events by
  // name, checked with the structure; a scene that gives them other values is refused).
  if (const auto now = events.switched_settings(); now != c.settings) {
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
      return s.empty() ? std::string("none") : s;
    };
    throw ConfigError("restart " + opt.restart_file + ": written with the settings " + list(c.settings) +
                      " switched by events, this run's events switch " + list(now) +
                      ": restart with the events of the writing run");
  }
  stepper.restore(c.state);
  t0 = c.state.t, seg = c.segment, iout = c.next_output;
}

}  // namespace

SimResult drive(Flowsheet& fs, DaeSystem& sys, const SimOptions& opt, const std::vector<int>& sens_ids,
                Stepper& stepper, std::chrono::steady_clock::time_point wall0) {
  const std::vector<double> t_out = output_times(opt);
  SimResult res;
  Recorder recorder(fs, sys, opt, sens_ids, res);
  res.stats.states = sys.size();
  res.stats.explicit_states = sys.full_size() - sys.size();
  res.stats.quadratures = sys.n_quadratures();
  auto record = [&](double t) {
    const Sample s = stepper.sample(t);
    recorder.record(t, s.y, s.yp, s.q, s.yS, s.qS);
  };
  auto check_flag = [&](int flag) {
    if (flag < 0) throw_step_failure(fs, sys, stepper.failure(flag));
  };
  EventMonitor events(fs, sys, opt.events, sens_ids);  // sets the flowsheet's parameters back however the run ends
  if (events.size() > 0)
    stepper.set_roots(
        events.size(),
        [&events](double t, const double* y, const double* yp, double* g) { return events.roots(t, y, yp, g); },
        events.directions());

  // Segments between breakpoints, each started anew (a kink of an input is never stepped over); an event ends a
  // segment early and the next starts at the event.
  const std::vector<double> ends = segment_ends(fs, opt);
  double t0 = 0.0;
  size_t iout = 0, seg = 0, iend = 0;
  if (!opt.restart_file.empty()) restart(opt, fs, sys, stepper, events, res, t0, seg, iout);
  while (iend < ends.size() && ends[iend] <= t0) ++iend;
  bool stopped = false;
  while (iend < ends.size() && !stopped) {
    const double t1 = ends[iend];
    sys.set_segment_start(t0);
    if (seg > 0) ++res.stats.reinits;
    check_flag(stepper.begin_segment(seg, t0, t1, res.stats));
    while (iout < t_out.size() && t_out[iout] <= t0 + 1e-12 * std::max(1.0, t0)) {
      if (seg == 0) record(t_out[iout]);
      ++iout;
    }
    double t = t0;
    EventMonitor::Outcome event;
    // An event that crossed with the one that ended the last segment fires now, from the values after that one.
    if (events.pending()) event = events.fire_pending(t0, stepper.sample(t0), res.events);
    while (t < t1 && !event.fired) {
      const bool to_output = iout < t_out.size() && t_out[iout] <= t1;
      const int flag = stepper.advance(to_output ? t_out[iout] : t1, t);
      check_flag(flag);
      if (interrupt_requested()) throw Interrupted(t);
      if (stepper.root_found(flag)) {
        event = events.fire(t, stepper.roots(), stepper.sample(t), res.events);
        if (event.fired) break;
        continue;
      }
      if (to_output && t >= t_out[iout] * (1 - 1e-14)) {
        record(t_out[iout]);
        ++iout;
      }
      if (stepper.segment_done(flag, t, t1)) break;
    }
    stepper.end_segment(t0, event.fired ? t : t1);
    ++seg;
    if (event.fired) {
      stopped = event.stop;
      if (stopped && (res.t.empty() || res.t.back() < t)) record(t);
      if (!stopped) stepper.jump_sensitivities(std::move(event.jump));
      t0 = t;
      continue;
    }
    if (is_checkpoint(opt, t1) && !opt.checkpoint_dir.empty())
      res.checkpoint_files.push_back(save_checkpoint(opt, fs, stepper, events, res, t1, seg, iout));
    t0 = t1;
    ++iend;
  }
  stepper.finish(res.stats);
  res.stats.residuals = sys.residual_count();
  res.stats.jacobians = sys.jacobian_count();
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  sys.end_run();
  return res;
}

}  // namespace granuflow::detail
