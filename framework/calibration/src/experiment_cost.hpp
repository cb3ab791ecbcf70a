// The weighted residuals (m - d) / σ of one experiment: the residual block Ceres minimizes, with the weights σ held
// fixed between reweighting passes.
#pragma once
#include <ceres/cost_function.h>

#include <algorithm>
#include <mutex>
#include <string>
#include <vector>

#include "experiment_model.hpp"

namespace granuflow::calib {

// The weighted residuals of one experiment; the residual block of Ceres.
class ExperimentCost : public ceres::CostFunction {
 public:
  ExperimentCost(ExperimentModel* model, int n, SigmaBasis basis) : model_(model), n_(n), basis_(basis) {
    set_num_residuals(model->rows());
    mutable_parameter_block_sizes()->push_back(n);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  // r = (m - d) / σ and, if J != nullptr, dr/dθ row-major. σ is fixed by the first evaluation (and by
  // reweight()): the loss is a fixed least-squares function between reweighting passes.
  void compute(const double* theta, double* r, double* J) const;

  // Residuals and Jacobian at θ, from the last Jacobian evaluation if it was there.
  void at(const double* theta, std::vector<double>& r, std::vector<double>& J) const;

  // Evaluates at θ ahead of Ceres (StageRun's evaluation callback), keeping the result, or the error, for the
  // Evaluate() at that θ that follows; the same compute() either way, so the numbers do not change.
  void prepare(const double* theta, bool jacobian) const;
  // Seconds the last evaluation of this kind took (0 before the first): StageRun starts the slowest first.
  double last_seconds(bool jacobian) const { return seconds_[jacobian]; }

  // SigmaBasis::kModel: σ_rel |m| at the last Jacobian point (which must be `theta`); rescales the cached
  // residuals and Jacobian to the new weights. Returns the largest relative change of a σ.
  double reweight(const double* theta) const;

  const std::vector<double>& sigma() const { return sigma_; }
  void set_sigma(const std::vector<double>& s) { sigma_ = s; }

  std::string last_error() const {
    std::lock_guard<std::mutex> lock(error_mutex_);
    return last_error_;
  }
  ExperimentModel& model() const { return *model_; }

 private:
  ExperimentModel* model_;
  int n_;
  SigmaBasis basis_;
  bool cached(const double* theta) const {
    return last_theta_.size() == size_t(n_) && std::equal(last_theta_.begin(), last_theta_.end(), theta);
  }
  std::vector<double> sigma_at(const std::vector<double>& m) const;
  void weigh(const std::vector<double>& m, const std::vector<double>* dm, double* r, double* J) const;

  mutable std::vector<double> sigma_, last_theta_, last_m_, last_dm_, last_r_, last_J_;
  // prepare()'s result: θ, whether with the Jacobian, r, J, or the error it threw.
  mutable std::vector<double> ready_theta_, ready_r_, ready_J_;
  mutable bool ready_ = false, ready_jacobian_ = false;
  mutable std::string ready_error_;
  mutable double seconds_[2] = {0.0, 0.0};
  mutable std::mutex error_mutex_;
  mutable std::string last_error_;
};

}  // namespace granuflow::calib
