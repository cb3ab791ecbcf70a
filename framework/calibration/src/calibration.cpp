// The staged driver of calibrate(): each stage run in turn from the estimates of the ones before, restarted from
// lower points that scans of flat parameters or profiles find, and what the user must know about it noted.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "calibration_internal.hpp"
#include "granuflow/errors.hpp"
#include "profile.hpp"
#include "stage_run.hpp"

namespace granuflow {

using calib::Clock;
using calib::fmt;
using calib::half_sum_squares;
using calib::make_space;
using calib::profile_parameter;
using calib::run_stage;
using calib::seconds_since;
using calib::Space;
using calib::StageRun;
using calib::start_theta;

namespace {

// A start value outside the bounds of a stage that frees it is bad input (not clipped silently).
void check_start(const Flowsheet& fs, const std::vector<Stage>& stages, const std::map<std::string, double>& start) {
  for (const auto& st : stages) {
    const Space sp = make_space(fs, st);
    for (int k = 0; k < sp.size(); ++k) {
      const auto it = start.find(sp.names[k]);
      if (it == start.end()) continue;
      if (!(it->second >= sp.lower[k] && it->second <= sp.upper[k]))
        throw ConfigError(violation("start." + sp.names[k], it->second, fs.param_spec(fs.param_id(sp.names[k])).unit,
                                    fmt(sp.lower[k], 12) + " <= " + sp.names[k] + " <= " + fmt(sp.upper[k], 12) +
                                        " (bounds of stage '" + st.name + "')"));
    }
  }
}

// One stage of calibrate(), run from the estimates of the stages before it.
struct StageDriver {
  const Scene& scene;
  const Registry<Unit>& reg;
  const std::vector<Experiment>& exps;
  const Stage& stage;
  const CalibrationOptions& opt;
  const Flowsheet& fs;
  CalibrationResult& out;
  // Free parameters of this stage that a later stage frees again, each with the last such stage: the descent from
  // the edge of a flat region here is left to it (its data may determine the parameter).
  std::map<std::string, std::string> freed_later;
  const std::map<std::string, double> before;  // the parameters as this stage found them
  // Flat parameters left to a later stage that go on at their value from before this stage (see scan_flat_and_restart)
  std::map<std::string, double> handed_on;
  bool flat_scanned = false;  // the flat parameters of `r` were scanned (not so with max_restarts 0, or used up)
  std::vector<std::vector<double>> sigmas;
  StageResult r;
  long extra_sims = 0, extra_sens = 0;  // scans, profiles and runs a restart replaced

  StageDriver(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps, const Stage& stage,
              const CalibrationOptions& opt, CalibrationResult& out, std::map<std::string, std::string> freed_later)
      : scene(scene),
        reg(reg),
        exps(exps),
        stage(stage),
        opt(opt),
        fs(*scene.flowsheet),
        out(out),
        freed_later(std::move(freed_later)),
        before(out.parameters),
        r(run_stage(scene, reg, exps, stage, opt, out.parameters, true, opt.max_iterations, nullptr, &sigmas)) {}

  // Restarts from a lower point of the loss: a scan over the bounds of a parameter the loss is flat in at the
  // estimate (the start may lie in a flat region), or a profile point of the last stage below the estimate.
  bool restart_from(std::map<std::string, double> from, const std::string& why) {
    std::vector<std::vector<double>> sig;
    const double old_cost = r.cost;
    StageResult again = run_stage(scene, reg, exps, stage, opt, from, true, opt.max_iterations, nullptr, &sig);
    if (!(again.cost < old_cost)) {  // weights differ between runs: only an actual improvement replaces it
      extra_sims += again.simulations, extra_sens += again.sensitivity_solves;
      r.notes.push_back(why + "; the restart ended at a cost of " + fmt(again.cost, 6) + ", no lower: kept");
      return false;
    }
    extra_sims += r.simulations, extra_sens += r.sensitivity_solves;
    for (const auto& p : r.profiles) extra_sims += p.simulations, extra_sens += p.sensitivity_solves;
    again.notes = r.notes;
    again.restarts = r.restarts + 1;
    again.sensitivity_retries += r.sensitivity_retries;
    again.notes.push_back(why + "; restarted from there: cost " + fmt(old_cost, 6) + " -> " + fmt(again.cost, 6) +
                          " (Δχ² = " + fmt(2 * (old_cost - again.cost), 3) + ")");
    r = std::move(again);
    flat_scanned = false;
    handed_on.clear();
    sigmas = std::move(sig);
    out.parameters = std::move(from);
    return true;
  }

  std::string unit_of(const std::string& name) const { return fs.param_spec(fs.param_id(name)).unit; }

  // The flat parameters that no later stage frees again: this stage's to leave.
  std::vector<std::string> own_flat() const {
    std::vector<std::string> names;
    for (const auto& name : r.flat)
      if (!freed_later.count(name)) names.push_back(name);
    return names;
  }

  void scan_flat_and_restart() {
    while (!r.flat.empty() && opt.flat_scan_points > 0 && r.restarts < opt.max_restarts) {
      // The scan: the lowest point, and the edge of the flat region (the scan point nearest the estimate, in units
      // of the span, where the loss responds), from where the stage's descent can find a narrow valley the scan's
      // spacing misses. That descent is left to a later stage that frees the parameter again: its data may
      // determine it, and it starts from there anyway. Such a parameter is also tried at its value from before
      // this stage: where the loss is the same there (within restart_delta_chi2), the data of this stage prefer
      // nothing, and it goes on at that value rather than where the descent drifted it on the plateau (often a
      // bound, far from where the later stage's data put it).
      std::string best_name, edge_name;
      double best_value = 0, best_cost = r.cost - 0.5 * opt.restart_delta_chi2, edge_value = 0, edge_distance = 2;
      handed_on.clear();
      for (const auto& name : r.flat) {
        const Space sp = make_space(fs, stage);
        const int k = static_cast<int>(std::find(sp.names.begin(), sp.names.end(), name) - sp.names.begin());
        StageRun run(scene, reg, exps, stage, opt, out.parameters);
        run.set_sigmas(sigmas);
        std::vector<double> th = start_theta(sp, out.parameters), res;
        const double at = th[k], span = sp.theta_upper(k) - sp.theta_lower(k);
        const bool later = freed_later.count(name) > 0;
        const double prior = later ? sp.to_theta(k, before.at(name)) : at;
        std::vector<double> points;  // evenly over the bounds, then the value from before unless among them
        for (int j = 0; j < opt.flat_scan_points; ++j)
          points.push_back(sp.theta_lower(k) + span * j / (opt.flat_scan_points - 1));
        if (prior >= sp.theta_lower(k) && prior <= sp.theta_upper(k) &&
            std::find(points.begin(), points.end(), prior) == points.end())
          points.push_back(prior);
        for (const double point : points) {
          th[k] = point;
          if (th[k] == at) continue;  // the estimate itself (often a bound): neither lower nor responding
          try {
            run.evaluate(th, res, nullptr, opt.num_threads);
          } catch (const SolverError&) {  // the model fails there: not a point to restart from
            continue;
          }
          const double c = half_sum_squares(res);
          if (c < best_cost) best_cost = c, best_name = name, best_value = sp.to_p(k, th[k]);
          const bool responds = std::abs(c - r.cost) > 0.5 * opt.restart_delta_chi2;
          if (responds && std::abs(th[k] - at) / span < edge_distance && !later)
            edge_distance = std::abs(th[k] - at) / span, edge_name = name, edge_value = sp.to_p(k, th[k]);
          if (th[k] == prior && later && !responds) handed_on[name] = before.at(name);
        }
        extra_sims += run.simulations();
      }
      flat_scanned = true;
      std::map<std::string, double> from = out.parameters;
      std::string why;
      if (!best_name.empty()) {
        why = "the loss was flat in " + best_name + " at " + fmt(out.parameters.at(best_name)) + " " +
              unit_of(best_name) + " (nothing the stage watches responds to it there); a scan over its bounds found " +
              "a cost lower by Δχ² = " + fmt(2 * (r.cost - best_cost), 3) + " at " + fmt(best_value) + " " +
              unit_of(best_name);
        from[best_name] = best_value;
      } else if (!edge_name.empty()) {
        why = "the loss was flat in " + edge_name + " at " + fmt(out.parameters.at(edge_name)) + " " +
              unit_of(edge_name) + " (nothing the stage watches responds to it there); a scan over its bounds " +
              "found it responding from " + fmt(edge_value) + " " + unit_of(edge_name) + " on";
        from[edge_name] = edge_value;
      } else {
        break;  // flat across the bounds: the data of the stage do not determine it
      }
      if (!restart_from(from, why)) break;
    }
    for (const auto& [name, value] : handed_on) out.parameters[name] = value;
  }

  // Profiles of the flagged estimates (the last stage's); a profile point below the estimate's cost restarts the stage.
  void profile_and_restart() {
    while (true) {
      std::map<std::string, double> lowest;
      double lowest_dchi = -opt.restart_delta_chi2;
      r.profiles.clear();
      for (size_t k = 0; k < r.estimates.size(); ++k) {
        if (r.estimates[k].flag.empty()) continue;
        Profile p = profile_parameter(scene, reg, exps, stage, opt, out.parameters, r, static_cast<int>(k), sigmas,
                                      lowest, lowest_dchi);
        r.profiles.push_back(std::move(p));
      }
      if (lowest.empty() || r.restarts >= opt.max_restarts) break;
      std::string moved;
      for (const auto& e : r.estimates)
        if (lowest.count(e.name) && lowest.at(e.name) != e.value)
          moved += (moved.empty() ? "" : ", ") + e.name + " = " + fmt(lowest.at(e.name)) + " " + unit_of(e.name);
      if (!restart_from(lowest, "a profile found a cost lower than the estimate's by Δχ² = " + fmt(-lowest_dchi, 3) +
                                    " (at " + moved + ")"))
        break;
    }
    for (auto& p : r.profiles) {
      const auto it =
          std::find_if(r.estimates.begin(), r.estimates.end(), [&](const Estimate& e) { return e.name == p.name; });
      Estimate& e = *it;
      e.identifiable = p.verdict != "unidentifiable" && std::isfinite(e.se);
      e.flag += "; profile: " + p.verdict + " (Δχ² < " + fmt(opt.profile_delta_chi2, 3) + " over [" + fmt(p.lower_95) +
                ", " + fmt(p.upper_95) + "]" + (p.bounded_below ? "" : ", open below") +
                (p.bounded_above ? "" : ", open above") + ")";
    }
  }

  // What the user must know about this stage.
  void add_notes() {
    const std::string w = "stage '" + r.name + "': ";
    std::vector<std::string> left_to_later;  // in the stage's notes, not warned: a later stage decides them
    const std::string scanned = flat_scanned ? " and a scan over its bounds found no lower cost" : "";
    for (const auto& name : r.flat) {
      const auto e =
          std::find_if(r.estimates.begin(), r.estimates.end(), [&](const Estimate& x) { return x.name == name; });
      const std::string flat_at =
          "the loss is flat in " + name + " at its estimate " + fmt(e->value) + " " + unit_of(name) + scanned;
      if (const auto later = freed_later.find(name); later != freed_later.end())
        left_to_later.push_back(flat_at + ": the data of this stage do not determine it; " +
                                (handed_on.count(name)
                                     ? "it goes on at its value from before this stage, " + fmt(handed_on.at(name)) +
                                           " " + unit_of(name) + ", where the loss is the same, and "
                                     : "") +
                                "stage '" + later->second + "' frees it again and decides it");
      else
        r.notes.push_back(flat_at + ": the data of this stage do not determine it from here (try other starts or " +
                          "bounds)");
    }
    if (!r.moved) {
      std::string names;
      for (const auto& e : r.estimates) names += (names.empty() ? "" : ", ") + e.name;
      r.notes.push_back(
          "no free parameter moved from its start (" + names + ")" +
          (r.flat.empty() ? ": the start was already the optimum" : ": the start lies in a flat region of the loss"));
    }
    if (r.sensitivity_retries > 0)
      r.notes.push_back(std::to_string(r.sensitivity_retries) +
                        " sensitivity solves failed and were retried with smaller steps or replaced by central "
                        "differences");
    for (const auto& n : r.notes)
      if (n.rfind("no free parameter moved", 0) != 0 || !own_flat().empty()) out.warnings.push_back(w + n);
    r.notes.insert(r.notes.end(), left_to_later.begin(), left_to_later.end());
  }

  // Into the calibration's result, with the simulations of scans, profiles and replaced runs.
  void finish() {
    // USER_SUCCESS is the small-change callback of StageRun::solve: converged by this calibration's own criterion
    if (r.termination != "CONVERGENCE" && r.termination != "USER_SUCCESS" && out.status == "ok") {
      out.status = "no_convergence";
      out.message = "stage '" + r.name + "': " + r.message;
    }
    r.simulations += extra_sims;
    r.sensitivity_solves += extra_sens;
    out.simulations += r.simulations;
    out.sensitivity_solves += r.sensitivity_solves;
    for (const auto& p : r.profiles) out.simulations += p.simulations, out.sensitivity_solves += p.sensitivity_solves;
    out.stages.push_back(std::move(r));
  }
};

}  // namespace

CalibrationResult calibrate(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                            const std::vector<Stage>& stages, const CalibrationOptions& opt,
                            const std::map<std::string, double>& start) {
  opt.validate();
  check_experiments(*scene.flowsheet, exps);
  const auto t0 = Clock::now();
  if (stages.empty()) throw ConfigError("calibrate: no stages");
  if (exps.empty()) throw ConfigError("calibrate: no experiments");
  const Flowsheet& fs = *scene.flowsheet;
  CalibrationResult out;
  for (const auto& [k, v] : start) {
    fs.param_id(k);
    out.parameters[k] = v;
  }
  check_start(fs, stages, start);
  for (const auto& st : stages)
    for (const auto& f : st.free)
      if (!out.parameters.count(f.name)) out.parameters[f.name] = fs.param(f.name);
  for (size_t s = 0; s < stages.size(); ++s) {
    std::map<std::string, std::string> freed_later;
    for (size_t t = s + 1; t < stages.size(); ++t)
      for (const auto& f : stages[t].free) freed_later[f.name] = stages[t].name;
    StageDriver driver(scene, reg, exps, stages[s], opt, out, std::move(freed_later));
    driver.scan_flat_and_restart();
    if (s + 1 == stages.size() && opt.profile) driver.profile_and_restart();
    driver.add_notes();
    driver.finish();
  }
  if (const auto unused = unused_observations(exps, stages); !unused.empty()) {
    std::string list;
    for (const auto& u : unused) list += (list.empty() ? "" : ", ") + u;
    out.warnings.push_back("data that no stage uses: " + list +
                           "; add them to a stage's observables (a stage without observables uses all) or leave them "
                           "out of the experiments");
  }
  out.wall_time_s = seconds_since(t0);
  return out;
}

}  // namespace granuflow
