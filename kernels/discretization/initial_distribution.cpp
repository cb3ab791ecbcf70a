#include "discretization/initial_distribution.hpp"

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

std::string to_string(Binning b) {
  return b == Binning::kMoments ? "moments" : b == Binning::kNumber ? "number" : "mass";
}

Binning binning_from_string(const std::string& s) {
  for (Binning b : {Binning::kMoments, Binning::kNumber, Binning::kMass})
    if (to_string(b) == s) return b;
  throw ConfigError("initial binning '" + s + "': not one of moments, number, mass");
}

}  // namespace granuflow::kernels
