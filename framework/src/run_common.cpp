#include "run_common.hpp"

#include <cmath>

#include "granuflow/errors.hpp"

namespace granuflow::detail {

std::vector<int> sensitivity_ids(const Flowsheet& fs, const SimOptions& opt) {
  std::vector<int> ids;
  for (const auto& name : opt.sensitivities) {
    const int id = fs.param_id(name);
    if (fs.has_input(id))
      throw ConfigError("sensitivity parameter '" + name +
                        "' is a time-dependent input; only constants can be differentiated");
    ids.push_back(id);
  }
  return ids;
}

std::vector<double> output_times(const SimOptions& opt) {
  std::vector<double> t_out = opt.t_out;
  if (t_out.empty())
    for (int i = 0; i < opt.n_out; ++i) t_out.push_back(opt.t_end * i / (opt.n_out - 1));
  return t_out;
}

// 100 times the absolute tolerance: what an integrator may leave below zero on a state that tends to zero. A state
// that is not a finite number is named as such (a NaN fails every comparison and was reported as negative).
void check_nonnegative(const Flowsheet& fs, const SimOptions& opt, double t, const std::vector<double>& y) {
  for (size_t i = 0; i < y.size(); ++i) {
    const StateSpec& st = fs.state_spec(static_cast<int>(i));
    const bool finite = std::isfinite(y[i]);
    if (finite && (!st.nonnegative || y[i] >= -100.0 * opt.atol * st.scale)) continue;
    const std::string unit = fs.units()[fs.state_unit(static_cast<int>(i))].name;
    if (!finite)
      throw SolverError("unit '" + unit + "': state " + st.name + " = " + fmt_num(y[i]) + " at t = " + fmt_num(t) +
                            " s is not a finite number: a rate or closure of the unit gave it; check the size grid "
                            "and the ranges the unit's closures hold for",
                        t, unit, 0.0);
    throw SolverError("unit '" + unit + "': inventory " + st.name + " = " + fmt_num(y[i]) + " " + st.unit +
                          " at t = " + fmt_num(t) + " s is negative beyond the solver tolerance (" +
                          fmt_num(100.0 * opt.atol * st.scale) + " " + st.unit +
                          "): a rate moving it is not positivity-preserving there; check the size grid and the "
                          "ranges the unit's closures hold for",
                      t, unit, 0.0);
  }
}

Recorder::Recorder(Flowsheet& fs, DaeSystem& sys, const SimOptions& opt, std::vector<int> sens_ids, SimResult& res)
    : fs_(fs), sys_(sys), opt_(opt), sens_ids_(std::move(sens_ids)), res_(res) {
  const int n_full = sys.full_size(), no = static_cast<int>(fs.output_names().size()), ns = sens_ids_.size();
  y_full_.resize(n_full), yp_full_.resize(n_full), out_.resize(no);
  q_zero_.assign(std::max(sys.n_quadratures(), 1), 0.0);
  s_full_.assign(ns, std::vector<double>(n_full));
  dout_.assign(ns, std::vector<double>(no));
  qs_zero_.assign(ns, std::vector<double>(std::max(sys.n_quadratures(), 1), 0.0));
  res.state_names = fs.state_names();
  res.output_names = fs.output_names();
  res.sens_params = opt.sensitivities;
  // The result's arrays at their final size (no reallocation and copy as output times are added).
  const size_t nt = output_times(opt).size();
  res.t.reserve(nt), res.y.reserve(nt * n_full), res.yp.reserve(nt * n_full), res.outputs.reserve(nt * no);
  if (ns > 0) res.sens.reserve(nt * ns * n_full), res.output_sens.reserve(nt * ns * no);
  // The inventories that must not fall below zero, with what the solver may leave there (check_nonnegative).
  for (int i = 0; i < n_full; ++i) {
    const StateSpec& st = fs.state_spec(i);
    if (st.nonnegative) floors_.push_back({i, -100.0 * opt.atol * st.scale});
  }
}

void Recorder::record(double t, const double* y, const double* yp, const double* q, const double* const* yS,
                      const double* const* qS) {
  const int ns = static_cast<int>(sens_ids_.size()), no = static_cast<int>(out_.size());
  if (!q) q = q_zero_.data();
  sys_.extend(t, y, yp, y_full_.data(), yp_full_.data());
  // IDAS keeps the declared non-negative inventories at zero or above at its steps (constraints); an output time
  // between steps is interpolated and may dip below zero within the tolerance. It is recorded as the integrator
  // gives it: zeroing it would break the exact conservation of number and mass the schemes guarantee.
  for (const auto& [i, floor] : floors_)
    if (!(y_full_[i] >= floor)) check_nonnegative(fs_, opt_, t, y_full_);  // throws, naming the state
  res_.t.push_back(t);
  res_.y.insert(res_.y.end(), y_full_.begin(), y_full_.end());
  res_.yp.insert(res_.yp.end(), yp_full_.begin(), yp_full_.end());
  if (no > 0) sys_.report(t, y_full_.data(), yp_full_.data(), q, out_.data());
  for (double& v : out_)
    if (!std::isfinite(v)) v = std::nan("");
  res_.outputs.insert(res_.outputs.end(), out_.begin(), out_.end());
  if (ns == 0) return;
  std::vector<double*> dst(ns), dsto(ns);
  std::vector<const double*> qsrc(ns), sf(ns);
  for (int k = 0; k < ns; ++k) {
    dst[k] = s_full_[k].data(), dsto[k] = dout_[k].data(), sf[k] = s_full_[k].data();
    qsrc[k] = qS ? qS[k] : qs_zero_[k].data();
  }
  sys_.extend_sensitivities(t, y, yp, sens_ids_, yS, dst.data());
  for (int k = 0; k < ns; ++k) res_.sens.insert(res_.sens.end(), s_full_[k].begin(), s_full_[k].end());
  if (no > 0) {
    sys_.report_sensitivities(t, y_full_.data(), yp_full_.data(), q, sens_ids_, sf.data(), qsrc.data(), dsto.data());
    for (int k = 0; k < ns; ++k) res_.output_sens.insert(res_.output_sens.end(), dout_[k].begin(), dout_[k].end());
  }
}

}  // namespace granuflow::detail
