// The calibration's reports: a one-line summary and the full table of stages, estimates, correlations, notes and
// profiles.
#include <iomanip>
#include <sstream>

#include "calibration_internal.hpp"

namespace granuflow {

using calib::fmt;

std::string CalibrationResult::brief() const {
  std::ostringstream os;
  os << "calibration " << status << ": " << stages.size() << " stage" << (stages.size() == 1 ? "" : "s");
  if (!stages.empty())
    os << ", final cost " << fmt(stages.back().cost, 6) << " (reduced chi2 " << fmt(stages.back().chi2_reduced, 3)
       << ")";
  os << ", " << simulations << " simulations (" << sensitivity_solves << " with sensitivities), " << fmt(wall_time_s, 3)
     << " s";
  std::string flagged;
  if (!stages.empty())
    for (const auto& e : stages.back().estimates)
      if (!e.identifiable) flagged += (flagged.empty() ? "" : ", ") + e.name;
  if (!flagged.empty()) os << "; unidentifiable: " << flagged;
  if (!warnings.empty()) os << "; " << warnings.size() << " warning" << (warnings.size() == 1 ? "" : "s");
  return os.str();
}

std::string CalibrationResult::full_report() const {
  std::ostringstream os;
  os << brief() << "\n";
  if (!message.empty()) os << message << "\n";
  for (const auto& w : warnings) os << "warning: " << w << "\n";
  os << "\nstage                         iter   cost start     cost end  chi2_red  sims  sens   time_s  jacobian\n";
  for (const auto& s : stages)
    os << std::left << std::setw(28) << s.name << std::right << std::setw(6) << s.iterations << std::setw(13)
       << fmt(s.initial_cost, 6) << std::setw(13) << fmt(s.cost, 6) << std::setw(10) << fmt(s.chi2_reduced, 3)
       << std::setw(6) << s.simulations << std::setw(6) << s.sensitivity_solves << std::setw(9) << fmt(s.wall_time_s, 3)
       << "  " << s.jacobian_method << " (" << s.termination << ")\n";
  for (const auto& s : stages) {
    os << "\n[" << s.name << "] observables:";
    if (s.observables.empty()) os << " all";
    for (const auto& o : s.observables) os << " " << o;
    os << "\nparameter                  start         estimate      std.error     rel.se   transform  identifiable\n";
    for (const auto& e : s.estimates)
      os << std::left << std::setw(22) << e.name << std::right << std::setw(14) << fmt(e.start, 6) << std::setw(14)
         << fmt(e.value, 6) << std::setw(14) << fmt(e.se, 4) << std::setw(11) << fmt(e.rel_se, 3) << std::setw(11)
         << to_string(e.transform) << "  " << (e.identifiable ? "yes" : "NO")
         << (e.flag.empty() ? "" : "  [" + e.flag + "]") << "\n";
    const size_t n = s.estimates.size();
    if (!s.correlation.empty()) {
      os << "correlation:\n";
      for (size_t i = 0; i < n; ++i) {
        os << "  " << std::left << std::setw(22) << s.estimates[i].name << std::right;
        for (size_t k = 0; k < n; ++k)
          os << std::setw(8) << std::fixed << std::setprecision(3) << s.correlation[i * n + k];
        os.unsetf(std::ios::fixed);
        os << "\n";
      }
    }
    for (const auto& n : s.notes) os << "note: " << n << "\n";
    for (const auto& p : s.profiles) {
      os << "profile of " << p.name << " (" << p.verdict << "):";
      for (size_t i = 0; i < p.values.size(); ++i) os << " " << fmt(p.values[i]) << ":" << fmt(p.delta_chi2[i], 3);
      os << "\n";
    }
  }
  return os.str();
}

}  // namespace granuflow
