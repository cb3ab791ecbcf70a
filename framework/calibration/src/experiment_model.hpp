// One experiment's model over a stage's free parameters: the parameter space θ <-> p of the stage, and the
// experiment's rows of the loss with the model (and dm/dθ) at them.
#pragma once
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "granuflow/calibration.hpp"
#include "granuflow/simulator.hpp"
#include "size_fraction.hpp"

namespace granuflow::calib {

// The free parameters of a stage and the map θ <-> p.
struct Space {
  std::vector<std::string> names;
  std::vector<Transform> transform;
  std::vector<bool> logarithmic;
  std::vector<double> lower, upper;  // SI

  int size() const { return static_cast<int>(names.size()); }
  double to_p(int k, double th) const { return transform[k] == Transform::kLog ? std::exp(th) : th; }
  double to_theta(int k, double p) const { return transform[k] == Transform::kLog ? std::log(p) : p; }
  double dp_dtheta(int k, double th) const { return transform[k] == Transform::kLog ? std::exp(th) : 1.0; }
  double theta_lower(int k) const { return to_theta(k, lower[k]); }
  double theta_upper(int k) const { return to_theta(k, upper[k]); }
};

Space make_space(const Flowsheet& fs, const Stage& stage);

// One experiment on its own clone of the scene: the rows of the stage's loss and the model at them.
class ExperimentModel {
 public:
  ExperimentModel(const Scene& scene, const Registry<Unit>& reg, const Experiment& e,
                  const std::vector<std::string>& observables, const Space& space,
                  const std::map<std::string, double>& fixed, const CalibrationOptions& opt);

  const std::string& name() const { return name_; }
  int rows() const { return static_cast<int>(data_.size()); }
  const std::vector<double>& data() const { return data_; }
  double sigma_abs(int r) const { return sigma_abs_[r]; }
  double sigma_rel(int r) const { return sigma_rel_[r]; }
  long simulations() const { return sims_; }
  long sensitivity_solves() const { return sens_; }

  // Model at the rows for free parameters θ; dm/dθ (row-major rows x n) when `dm` != nullptr.
  void run(const double* theta, std::vector<double>& m, std::vector<double>* dm);

  long retries() const { return retries_; }

 private:
  struct Obs {
    const Observation* src = nullptr;
    bool state = false;
    int index = 0;
    int q3 = -1;  // a measured size distribution's point, unit.Q3(size): index into q3_ (size_fraction.hpp)
    std::vector<int> samples, time_index;
  };

  double clamp_p(int k, double p) const { return std::min(std::max(p, space_.lower[k]), space_.upper[k]); }

  SimResult sensitivity_solve(const SimOptions& o);

  // dm/dθ by central differences in θ (one-sided at a bound): 2 plain simulations per free parameter. The
  // flowsheet holds the parameters of θ before and after.
  void central_differences(const double* theta, std::vector<double>& dm);

  void extract(const SimResult& r, std::vector<double>& m, std::vector<double>* dm);
  // Row of an observation unit.Q3(size) at output time `it`: the model m and dm/dp (n values) when dm != nullptr.
  void q3_row(int k, const SimResult& r, size_t it, const std::vector<double>& dz, double& m, double* dm) const;

  Scene scene_;
  const Space& space_;
  const CalibrationOptions& opt_;
  std::string name_;
  std::vector<Obs> obs_;
  std::vector<SizeFraction> q3_;
  std::vector<double> data_, sigma_abs_, sigma_rel_, t_out_;
  SimOptions sim_;
  bool any_output_ = false;
  long sims_ = 0, sens_ = 0, retries_ = 0;
};

}  // namespace granuflow::calib
