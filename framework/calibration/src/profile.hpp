// Profiles of the loss over one free parameter at a time (profile.cpp).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "granuflow/calibration.hpp"

namespace granuflow::calib {

// Δχ² profile of the loss over one free parameter of `stage`, the others re-optimized (warm-started outward).
// `lowest` (with its Δχ² in `lowest_dchi`) receives the parameters of the profile point of lowest cost when it is
// below `*lowest_dchi`: a profile that finds a lower cost than the estimate's shows the stage stopped short.
Profile profile_parameter(const Scene& scene, const Registry<Unit>& reg, const std::vector<Experiment>& exps,
                          const Stage& stage, const CalibrationOptions& opt,
                          const std::map<std::string, double>& optimum, const StageResult& at, int which,
                          const std::vector<std::vector<double>>& sigmas, std::map<std::string, double>& lowest,
                          double& lowest_dchi);

}  // namespace granuflow::calib
