#include "drying/drying_curves.hpp"

#include <cmath>
#include <memory>

#include "granuflow/errors.hpp"

namespace granuflow::kernels {

namespace {
const char* kReview = "paper 000, section 5.4.1 (fitted to measured drying curves; the default is the linear curve)";
}

std::vector<ParamSpec> CubicDryingCurve::params() const {
  return {{"A", "-", 1.0, -10.0, 10.0, "cubic drying curve: coefficient of eta (A + B + C = 1)", kReview},
          {"B", "-", 0.0, -10.0, 10.0, "cubic drying curve: coefficient of eta^2", kReview},
          {"C", "-", 0.0, -10.0, 10.0, "cubic drying curve: coefficient of eta^3", kReview}};
}

void CubicDryingCurve::check(const ClassState<double>&, const double* p, const std::string& where) const {
  const double sum = p[0] + p[1] + p[2];
  if (std::abs(sum - 1.0) > kCubicSumTolerance)
    throw ConfigError(where + ": cubic drying curve A + B + C = " + fmt_num(sum) + " (A = " + fmt_num(p[0]) +
                      ", B = " + fmt_num(p[1]) + ", C = " + fmt_num(p[2]) +
                      "): must be 1, so that the curve meets the constant-rate period at eta = 1 (paper 000, "
                      "section 5.4.1)");
}

std::vector<ParamSpec> GammaDryingCurve::params() const {
  return {
      {"gamma", "-", 1.0, 1e-3, 1e3, "gamma drying curve: shape parameter (1 = linear, > 1 dries faster)", kReview}};
}

void register_drying_curves(Registry<DryingCurve>& r) {
  r.add("linear", "linear normalized drying curve v = eta (paper 000, section 5.4.1; paper 001, Eq. (79))",
        [] { return std::make_unique<LinearDryingCurve>(); });
  r.add("cubic", "cubic normalized drying curve v = A eta + B eta^2 + C eta^3, A + B + C = 1 (paper 000, 5.4.1)",
        [] { return std::make_unique<CubicDryingCurve>(); });
  r.add("gamma", "one-parameter curve v = gamma eta / (1 + (gamma - 1) eta) (paper 000, section 5.4.1)",
        [] { return std::make_unique<GammaDryingCurve>(); });
}

}  // namespace granuflow::kernels
