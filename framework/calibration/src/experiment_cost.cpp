#include "experiment_cost.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>

#include "granuflow/interrupt.hpp"

namespace granuflow::calib {

bool ExperimentCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  double* J = jacobians && jacobians[0] ? jacobians[0] : nullptr;
  const double* theta = parameters[0];
  if (interrupt_flagged()) {
    // Interrupted (Ctrl-C): a value Ceres accepts, so that it reaches its iteration callback, which aborts
    // (StageRun::solve) without logging a failed evaluation; nothing of it is used, the stage then throws.
    std::fill(residuals, residuals + model_->rows(), 0.0);
    if (J) std::fill(J, J + size_t(model_->rows()) * n_, 0.0);
    ready_ = false;
    return true;
  }
  if (ready_ && (ready_jacobian_ || !J) && std::equal(ready_theta_.begin(), ready_theta_.end(), theta)) {
    ready_ = false;
    if (!ready_error_.empty()) {
      std::lock_guard<std::mutex> lock(error_mutex_);
      last_error_ = ready_error_;
      return false;
    }
    std::copy(ready_r_.begin(), ready_r_.end(), residuals);
    if (J) std::copy(ready_J_.begin(), ready_J_.end(), J);
    return true;
  }
  try {
    compute(theta, residuals, J);
    return true;
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_ = model_->name() + ": " + e.what();
    return false;
  }
}

void ExperimentCost::prepare(const double* theta, bool jacobian) const {
  const auto t0 = std::chrono::steady_clock::now();
  ready_ = false;
  ready_error_.clear();
  ready_theta_.assign(theta, theta + n_);
  ready_jacobian_ = jacobian;
  ready_r_.resize(model_->rows());
  ready_J_.resize(jacobian ? size_t(model_->rows()) * n_ : 0);
  try {
    compute(theta, ready_r_.data(), jacobian ? ready_J_.data() : nullptr);
  } catch (const std::exception& e) {
    ready_error_ = model_->name() + ": " + e.what();
  }
  ready_ = true;
  seconds_[jacobian] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void ExperimentCost::compute(const double* theta, double* r, double* J) const {
  const int rows = model_->rows();
  if (cached(theta)) {  // the point of the last Jacobian, e.g. where a reweighting pass starts: no new simulation
    weigh(last_m_, J ? &last_dm_ : nullptr, r, J);
    if (J) {
      last_r_.assign(r, r + rows);
      last_J_.assign(J, J + size_t(rows) * n_);
    }
    return;
  }
  std::vector<double> m, dm;
  model_->run(theta, m, J ? &dm : nullptr);
  if (sigma_.empty()) sigma_ = sigma_at(m);
  weigh(m, J ? &dm : nullptr, r, J);
  if (J) {
    last_theta_.assign(theta, theta + n_);
    last_m_ = std::move(m);
    last_dm_ = std::move(dm);
    last_r_.assign(r, r + rows);
    last_J_.assign(J, J + size_t(rows) * n_);
  }
}

void ExperimentCost::at(const double* theta, std::vector<double>& r, std::vector<double>& J) const {
  if (!cached(theta)) {
    r.resize(model_->rows());
    J.resize(size_t(model_->rows()) * n_);
    compute(theta, r.data(), J.data());
  }
  r = last_r_, J = last_J_;
}

double ExperimentCost::reweight(const double* theta) const {
  if (basis_ != SigmaBasis::kModel || !cached(theta)) return 0.0;
  const std::vector<double> s = sigma_at(last_m_);
  double change = 0.0;
  for (size_t i = 0; i < s.size(); ++i) change = std::max(change, std::abs(s[i] / sigma_[i] - 1.0));
  sigma_ = s;
  weigh(last_m_, &last_dm_, last_r_.data(), last_J_.data());
  return change;
}

std::vector<double> ExperimentCost::sigma_at(const std::vector<double>& m) const {
  const auto& d = model_->data();
  std::vector<double> s(m.size());
  for (size_t i = 0; i < m.size(); ++i) {
    const double base = basis_ == SigmaBasis::kModel ? m[i] : d[i];
    s[i] = model_->sigma_abs(i) > 0 ? model_->sigma_abs(i) : model_->sigma_rel(i) * std::max(std::abs(base), 1e-300);
  }
  return s;
}

void ExperimentCost::weigh(const std::vector<double>& m, const std::vector<double>* dm, double* r, double* J) const {
  const auto& d = model_->data();
  for (size_t i = 0; i < m.size(); ++i) r[i] = (m[i] - d[i]) / sigma_[i];
  if (J)
    for (size_t i = 0; i < m.size(); ++i)
      for (int k = 0; k < n_; ++k) J[i * n_ + k] = (*dm)[i * n_ + k] / sigma_[i];
}

}  // namespace granuflow::calib
