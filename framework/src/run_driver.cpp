#include "run_driver.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "granuflow/errors.hpp"
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

  // Segments between breakpoints, each started anew (a kink of an input is never stepped over).
  std::vector<double> ends = fs.breakpoints(opt.t_end);
  ends.push_back(opt.t_end);
  double t0 = 0.0;
  size_t iout = 0;
  for (size_t seg = 0; seg < ends.size(); ++seg) {
    const double t1 = ends[seg];
    sys.set_segment_start(t0);
    if (seg > 0) ++res.stats.reinits;
    check_flag(stepper.begin_segment(seg, t0, t1, res.stats));
    while (iout < t_out.size() && t_out[iout] <= t0 + 1e-12 * std::max(1.0, t0)) {
      if (seg == 0) record(t_out[iout]);
      ++iout;
    }
    double t = t0;
    while (t < t1) {
      const bool to_output = iout < t_out.size() && t_out[iout] <= t1;
      const int flag = stepper.advance(to_output ? t_out[iout] : t1, t);
      check_flag(flag);
      if (to_output && t >= t_out[iout] * (1 - 1e-14)) {
        record(t_out[iout]);
        ++iout;
      }
      if (stepper.segment_done(flag, t, t1)) break;
    }
    stepper.end_segment(t0, t1);
    t0 = t1;
  }
  stepper.finish(res.stats);
  res.stats.residuals = sys.residual_count();
  res.stats.jacobians = sys.jacobian_count();
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  sys.end_run();
  return res;
}

}  // namespace granuflow::detail
