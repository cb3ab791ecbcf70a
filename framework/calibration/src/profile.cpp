// Profiles of the loss over one free parameter at a time: a nonlinear view of identifiability beside the linear
// standard errors, and a check that the stage did not stop short of a lower cost.
#include "profile.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration_internal.hpp"
#include "granuflow/errors.hpp"
#include "stage_run.hpp"

namespace granuflow::calib {

Profile profile_parameter(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                          const Stage& stage, const CalibrationOptions& opt,
                          const std::map<std::string, double>& optimum, const StageResult& at, int which,
                          const std::vector<std::vector<double>>& sigmas, std::map<std::string, double>& lowest,
                          double& lowest_dchi) {
  const Estimate& e = at.estimates[which];
  Profile pr;
  pr.name = e.name;
  const bool log_like = e.transform == Transform::kLog || e.logarithmic;
  const double lo_th = e.transform == Transform::kLog ? std::log(e.lower) : e.lower;
  const double hi_th = e.transform == Transform::kLog ? std::log(e.upper) : e.upper;
  const double reach = opt.profile_max_offset * (log_like ? 1.0 : std::max(std::abs(e.theta), 1e-300));
  const double two_se = std::isfinite(e.se_theta) ? 2 * e.se_theta : std::numeric_limits<double>::infinity();
  Stage sub = stage;
  sub.free.erase(sub.free.begin() + which);
  sub.name = "profile of " + e.name;
  CalibrationOptions o = opt;
  o.profile = false;
  std::vector<std::pair<double, double>> pts{{e.theta, 0.0}};  // (θ, Δχ²)
  double dchi_2se[2] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  const auto to_p = [&](double th) { return e.transform == Transform::kLog ? std::exp(th) : th; };
  for (int side = -1; side <= 1; side += 2) {
    std::vector<double> offs;
    for (int j = opt.profile_max_points - 1; j >= 0; --j) offs.push_back(reach / std::pow(2.0, j));
    if (two_se < reach) offs.push_back(two_se);
    std::sort(offs.begin(), offs.end());
    offs.erase(std::unique(offs.begin(), offs.end()), offs.end());
    std::map<std::string, double> p = optimum;
    bool crossed = false;
    for (double off : offs) {
      double th = e.theta + side * off;
      const bool clipped = side < 0 ? th <= lo_th : th >= hi_th;
      if (clipped) th = side < 0 ? lo_th : hi_th;
      p[e.name] = to_p(th);
      double cost;
      try {
        if (sub.free.empty()) {
          StageRun run(scene, reg, exps, stage, o, p);
          run.set_sigmas(sigmas);
          std::vector<double> r, thv{th};
          run.evaluate(thv, r, nullptr, o.num_threads);
          cost = half_sum_squares(r);
          pr.simulations += run.simulations();
        } else {
          const StageResult sr = run_stage(scene, reg, exps, sub, o, p, false, std::min(o.max_iterations, 20), &sigmas);
          cost = sr.cost;
          pr.simulations += sr.simulations;
          pr.sensitivity_solves += sr.sensitivity_solves;
        }
      } catch (const SolverError&) {  // the model fails out there: the profile ends on this side
        break;
      } catch (const CalibrationError&) {
        break;
      }
      const double dchi = 2 * (cost - at.cost);
      if (dchi < lowest_dchi) lowest_dchi = dchi, lowest = p;
      pts.push_back({th, dchi});
      if (off == two_se) dchi_2se[(side + 1) / 2] = dchi;
      if (dchi > opt.profile_delta_chi2 && off >= std::min(two_se, reach)) {
        crossed = true;
        break;
      }
      if (clipped) break;
    }
    (side < 0 ? pr.bounded_below : pr.bounded_above) = crossed;
  }
  std::sort(pts.begin(), pts.end());
  for (const auto& [th, d] : pts) pr.values.push_back(to_p(th)), pr.delta_chi2.push_back(d);
  // Crossings of the threshold, linear in θ between profile points.
  const double thr = opt.profile_delta_chi2;
  size_t iopt = 0;
  while (iopt + 1 < pts.size() && pts[iopt].first != e.theta) ++iopt;
  pr.lower_95 = pr.values.front(), pr.upper_95 = pr.values.back();
  for (size_t i = iopt; i > 0; --i)
    if (pts[i - 1].second > thr) {
      const double f = (thr - pts[i].second) / (pts[i - 1].second - pts[i].second);
      pr.lower_95 = to_p(pts[i].first + f * (pts[i - 1].first - pts[i].first));
      break;
    }
  for (size_t i = iopt; i + 1 < pts.size(); ++i)
    if (pts[i + 1].second > thr) {
      const double f = (thr - pts[i].second) / (pts[i + 1].second - pts[i].second);
      pr.upper_95 = to_p(pts[i].first + f * (pts[i + 1].first - pts[i].first));
      break;
    }
  pr.linear_trustworthy = true;
  for (double d : dchi_2se)
    if (!(d > 2.0 && d < 8.0)) pr.linear_trustworthy = false;
  pr.verdict = !(pr.bounded_below && pr.bounded_above) ? "unidentifiable"
               : pr.linear_trustworthy                 ? "identifiable"
                                                       : "nonlinear";
  return pr;
}

}  // namespace granuflow::calib
