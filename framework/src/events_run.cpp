#include "events_run.hpp"

#include <algorithm>
#include <cmath>

#include "events.hpp"
#include "granuflow/errors.hpp"

namespace granuflow::detail {

EventMonitor::EventMonitor(Flowsheet& fs, DaeSystem& sys, const std::vector<EventSpec>& events,
                           const std::vector<int>& sens_ids)
    : fs_(fs), sys_(sys), events_(events), sens_ids_(sens_ids), fired_(events.size(), 0) {
  for (const auto& e : events_) {
    const EventQuantity q = find_event_quantity(fs, e.quantity, "event '" + e.name + "'");
    state_.push_back(q.state), output_.push_back(q.output);
  }
  y_full_.resize(sys.full_size()), yp_full_.resize(sys.full_size()), out_.resize(fs.n_outputs());
  q_zero_.assign(std::max(sys.n_quadratures(), 1), 0.0);
}

EventMonitor::~EventMonitor() {
  if (saved_values_.empty()) return;
  try {
    for (const auto& [id, v] : saved_values_) fs_.set_param_value(id, v);
    for (const auto& [name, input] : saved_inputs_) fs_.set_input(name, *input);
    sys_.reconfigure();
  } catch (...) {  // the values were the flowsheet's own before the run: setting them back cannot be refused
  }
}

std::vector<int> EventMonitor::directions() const {
  std::vector<int> d;
  for (const auto& e : events_) d.push_back(e.direction);
  return d;
}

bool EventMonitor::armed(size_t i) const {
  const EventSpec& e = events_[i];
  if (!e.repeat && fired_[i] > 0) return false;
  if (e.after.empty()) return true;
  for (size_t j = 0; j < events_.size(); ++j)
    if (events_[j].name == e.after) return fired_[j] > 0;
  return false;
}

int EventMonitor::roots(double t, const double* y, const double* yp, double* g) {
  bool outputs = false;
  for (size_t i = 0; i < events_.size(); ++i) outputs = outputs || (armed(i) && output_[i] >= 0);
  sys_.extend(t, y, yp, y_full_.data(), yp_full_.data());
  if (outputs) sys_.report(t, y_full_.data(), yp_full_.data(), q_zero_.data(), out_.data());
  for (size_t i = 0; i < events_.size(); ++i) {
    if (!armed(i)) {
      g[i] = 1.0;
      continue;
    }
    g[i] = (state_[i] >= 0 ? y_full_[state_[i]] : out_[output_[i]]) - events_[i].threshold;
    if (!std::isfinite(g[i])) return 1;  // recoverable: the integrator retries a shorter step
  }
  return 0;
}

// dt*/dp_k = -(dh/dp_k) / (dh/dt) for the event's quantity h at its root (the threshold does not depend on p):
// dh/dp_k is h's total sensitivity at t* (states' sensitivities and the parameter's own direction), dh/dt its rate
// along the trajectory (the unknowns' y', the explicit states and outputs differentiated along it by AD).
std::vector<double> EventMonitor::tau(size_t i, double t, const Sample& s) {
  const int nf = sys_.full_size(), ns = static_cast<int>(sens_ids_.size());
  const int nq = sys_.n_quadratures(), no = fs_.n_outputs();
  sys_.extend(t, s.y, s.yp, y_full_.data(), yp_full_.data());
  std::vector<double> dydt(nf);
  double* dydt_p = dydt.data();
  const std::vector<int> along{-1};  // a direction without a parameter: d/dt along the trajectory
  sys_.extend_sensitivities(t, s.y, s.yp, along, &s.yp, &dydt_p);
  std::vector<std::vector<double>> sf(ns, std::vector<double>(nf));
  std::vector<double*> sfp(ns);
  std::vector<const double*> sfc(ns);
  for (int k = 0; k < ns; ++k) sfp[k] = sf[k].data(), sfc[k] = sf[k].data();
  sys_.extend_sensitivities(t, s.y, s.yp, sens_ids_, s.yS, sfp.data());
  double rate = 0.0;
  std::vector<double> dh(ns);
  if (state_[i] >= 0) {
    rate = dydt[state_[i]];
    for (int k = 0; k < ns; ++k) dh[k] = sf[k][state_[i]];
  } else {
    std::vector<double> qdot(std::max(nq, 1), 0.0), d1(no);
    if (nq > 0) sys_.quadrature(t, s.y, s.yp, qdot.data());
    const double* q = s.q ? s.q : q_zero_.data();
    const double* dydt_c = dydt.data();
    const double* qdot_c = qdot.data();
    double* d1p = d1.data();
    sys_.report_sensitivities(t, y_full_.data(), yp_full_.data(), q, along, &dydt_c, &qdot_c, &d1p);
    rate = d1[output_[i]];
    std::vector<std::vector<double>> dout(ns, std::vector<double>(no)), qs0(ns, std::vector<double>(q_zero_.size()));
    std::vector<double*> dp(ns);
    std::vector<const double*> qsp(ns);
    for (int k = 0; k < ns; ++k) dp[k] = dout[k].data(), qsp[k] = s.qS ? s.qS[k] : qs0[k].data();
    sys_.report_sensitivities(t, y_full_.data(), yp_full_.data(), q, sens_ids_, sfc.data(), qsp.data(), dp.data());
    for (int k = 0; k < ns; ++k) dh[k] = dout[k][output_[i]];
  }
  if (!(std::abs(rate) > 0.0) || !std::isfinite(rate))
    throw SolverError("event '" + events_[i].name + "' at t = " + fmt_num(t) + " s: " + events_[i].quantity +
                          " does not change where it crosses the threshold (d/dt = " + fmt_num(rate) +
                          "), so the event time has no sensitivity; run without sensitivities or move the threshold",
                      t, fs_.units()[fs_.state_unit(std::max(0, state_[i]))].name, 0.0);
  std::vector<double> tau(ns);
  for (int k = 0; k < ns; ++k) tau[k] = -dh[k] / rate;
  return tau;
}

void EventMonitor::apply(const EventSpec& e) {
  for (const auto& a : e.set) {
    const int id = fs_.param_id(a.target);
    if (!saved_values_.count(id)) saved_values_[id] = fs_.param_value(id);
    if (fs_.has_input(id)) {  // the event switches the input to a constant for the rest of the run
      const auto [u, k] = fs_.param_location(id);
      if (!saved_inputs_.count(a.target)) saved_inputs_[a.target] = fs_.units()[u].inputs[k];
      fs_.clear_input(a.target);
    }
    fs_.set_param_value(id, a.value);
  }
}

EventMonitor::Outcome EventMonitor::fire(double t, const std::vector<int>& found, const Sample& s,
                                         std::vector<EventRecord>& log) {
  Outcome o;
  std::vector<size_t> firing;
  for (size_t i = 0; i < events_.size(); ++i)
    if (found[i] != 0 && armed(i)) firing.push_back(i);
  if (firing.empty()) return o;
  o.fired = true;
  if (!sens_ids_.empty()) {  // from the values before any action changes the system
    const int n = sys_.size(), nq = sys_.n_quadratures();
    o.jump.tau = tau(firing[0], t, s);
    o.jump.yp_before.assign(s.yp, s.yp + n);
    o.jump.qdot_before.assign(std::max(nq, 1), 0.0);
    if (nq > 0) sys_.quadrature(t, s.y, s.yp, o.jump.qdot_before.data());
  }
  bool changed = false;
  for (size_t i : firing) {
    const EventSpec& e = events_[i];
    ++fired_[i];
    log.push_back({e.name, e.phase.empty() ? e.name : e.phase, t});
    apply(e);
    changed = changed || !e.set.empty();
    o.stop = o.stop || e.stop;
  }
  if (changed) sys_.reconfigure();
  return o;
}

void EventMonitor::restore(const std::vector<EventRecord>& log) {
  bool changed = false;
  for (const auto& r : log)
    for (size_t i = 0; i < events_.size(); ++i)
      if (events_[i].name == r.name) {
        ++fired_[i];
        apply(events_[i]);
        changed = changed || !events_[i].set.empty();
      }
  if (changed) sys_.reconfigure();
}

}  // namespace granuflow::detail
