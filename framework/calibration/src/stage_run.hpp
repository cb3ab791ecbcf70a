// One stage of a calibration: its experiments' models and residual blocks, the bounded Levenberg-Marquardt solve
// with reweighting passes, and the statistics at its optimum.
#pragma once
#include <ceres/solver.h>
#include <ceres/types.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "experiment_cost.hpp"
#include "experiment_model.hpp"

namespace granuflow::calib {

// Everything of one stage: the models, their costs, and the Ceres solve.
struct StageRun {
  Space space;
  std::vector<std::unique_ptr<ExperimentModel>> models;
  std::vector<std::unique_ptr<ExperimentCost>> costs;
  std::vector<std::string> observables;
  std::string name;  // the stage's, for progress reports

  StageRun(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps, const Stage& stage,
           const CalibrationOptions& opt, const std::map<std::string, double>& fixed);

  long rows() const { return total(&ExperimentModel::rows); }
  long simulations() const { return total(&ExperimentModel::simulations); }
  long sensitivity_solves() const { return total(&ExperimentModel::sensitivity_solves); }
  long sensitivity_retries() const { return total(&ExperimentModel::retries); }

  // Every experiment's cost at θ evaluated ahead of Ceres on `threads` threads, the slowest (by its last
  // evaluation of this kind) first: Ceres hands out the experiments in their order, and a slow one taken last
  // leaves the other threads idle at the end of each evaluation.
  void prepare(const double* theta, bool jacobian, int threads);
  // All residuals and the Jacobian (rows stacked by experiment) at θ.
  void evaluate(const std::vector<double>& theta, std::vector<double>& r, std::vector<double>* J, int threads);
  ceres::Solver::Summary solve(std::vector<double>& theta, const CalibrationOptions& opt, int max_iterations);
  double reweight(const std::vector<double>& theta);
  std::vector<std::vector<double>> sigmas() const;
  void set_sigmas(const std::vector<std::vector<double>>& v);
  std::string first_error() const;

 private:
  template <class R>
  long total(R (ExperimentModel::*count)() const) const {
    long n = 0;
    for (const auto& m : models) n += (m.get()->*count)();
    return n;
  }
};

void clamp_theta(const Space& s, std::vector<double>& th);
std::vector<double> start_theta(const Space& s, const std::map<std::string, double>& p);

// Runs one stage from `params` (updated with the estimates); statistics at the optimum if `statistics`.
StageResult run_stage(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                      const Stage& stage, const CalibrationOptions& opt, std::map<std::string, double>& params,
                      bool statistics, int max_iterations, const std::vector<std::vector<double>>* sigmas = nullptr,
                      std::vector<std::vector<double>>* sigmas_out = nullptr);

}  // namespace granuflow::calib
