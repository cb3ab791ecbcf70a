// Validation of a calibrated model: its predictions at every sample of a set of experiments and the fit statistics
// per observable.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "calibration_internal.hpp"
#include "granuflow/simulator.hpp"
#include "size_fraction.hpp"

namespace granuflow {

using calib::parallel_for;

std::vector<Prediction> predict(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                                const std::map<std::string, double>& params, const CalibrationOptions& opt) {
  opt.validate();
  check_experiments(*scene.flowsheet, exps, false);  // the values are placeholders here
  std::vector<std::vector<Prediction>> per(exps.size());
  parallel_for(static_cast<int>(exps.size()), opt.num_threads, [&](int i) {
    const Experiment& e = exps[i];
    Scene s = clone_scene(scene, reg);
    Flowsheet& fs = *s.flowsheet;
    for (const auto& [k, v] : params) fs.set_param(k, v);
    for (const auto& [k, v] : e.settings) fs.set_param(k, v);
    std::set<double> times;
    double t_last = 0;
    for (const auto& o : e.observations)
      for (double t : o.t) times.insert(t), t_last = std::max(t_last, t);
    if (times.empty()) return;
    SimOptions so = s.options;
    so.t_out.assign(times.begin(), times.end());
    so.t_end = std::max({e.t_end, t_last, 1e-9});
    so.rtol = opt.rtol;
    so.atol = opt.atol;
    so.sensitivities.clear();
    const SimResult r = simulate(fs, so);
    const auto outs = fs.output_names();
    const auto states = fs.state_names();
    const size_t ns = states.size(), no = outs.size();
    for (const auto& o : e.observations) {
      Prediction p;
      p.experiment = e.name;
      p.observable = o.name;
      auto io = std::find(outs.begin(), outs.end(), o.name);
      auto is = std::find(states.begin(), states.end(), o.name);
      const auto q3 = calib::size_fraction(fs, o.name);
      if (!q3 && io == outs.end() && is == states.end()) observable_unit(fs, o.name);
      for (size_t j = 0; j < o.t.size(); ++j) {
        const size_t it = std::lower_bound(so.t_out.begin(), so.t_out.end(), o.t[j]) - so.t_out.begin();
        const double m = q3 ? calib::size_fraction_value(*q3, &r.outputs[it * no + q3->first_output], nullptr)
                         : io != outs.end() ? r.outputs[it * no + (io - outs.begin())]
                                            : r.y[it * ns + (is - states.begin())];
        p.t.push_back(o.t[j]);
        p.data.push_back(o.value[j]);
        p.model.push_back(m);
        p.sigma.push_back(o.sigma_abs > 0
                              ? o.sigma_abs
                              : o.sigma_rel * std::abs(opt.sigma_basis == SigmaBasis::kModel ? m : o.value[j]));
      }
      per[i].push_back(std::move(p));
    }
  });
  std::vector<Prediction> all;
  for (auto& v : per)
    for (auto& p : v) all.push_back(std::move(p));
  return all;
}

std::vector<FitStatistics> fit_statistics(const std::vector<Prediction>& preds) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::pair<double, double>>> by;
  for (const auto& p : preds) {
    if (!by.count(p.observable)) order.push_back(p.observable);
    auto& v = by[p.observable];
    for (size_t i = 0; i < p.data.size(); ++i)
      if (std::isfinite(p.data[i]) && std::isfinite(p.model[i])) v.push_back({p.data[i], p.model[i]});
  }
  std::vector<FitStatistics> out;
  for (const auto& name : order) {
    const auto& v = by[name];
    FitStatistics f;
    f.observable = name;
    f.n = static_cast<long>(v.size());
    if (v.empty()) {
      f.r2 = f.rmse = f.mean_abs_rel = std::numeric_limits<double>::quiet_NaN();
      out.push_back(f);
      continue;
    }
    double mean = 0;
    for (const auto& [d, m] : v) mean += d;
    mean /= v.size();
    double ss_res = 0, ss_tot = 0, rel = 0;
    for (const auto& [d, m] : v) {
      ss_res += (d - m) * (d - m);
      ss_tot += (d - mean) * (d - mean);
      rel += std::abs(m - d) / std::max(std::abs(d), 1e-300);
    }
    f.r2 = ss_tot > 0 ? 1 - ss_res / ss_tot : std::numeric_limits<double>::quiet_NaN();
    f.rmse = std::sqrt(ss_res / v.size());
    f.mean_abs_rel = rel / v.size();
    out.push_back(f);
  }
  return out;
}

}  // namespace granuflow
