#include "aggregation/callback.hpp"

#include <cmath>

namespace granuflow::kernels {

void CallbackKernel::factor(const ClassState<Jet>& s, const Jet* p, Jet* beta) const {
  const int n = s.n;
  std::vector<double> pv(specs_.size()), bv(size_t(n) * n);
  for (size_t k = 0; k < pv.size(); ++k) pv[k] = p[k].a;
  std::vector<std::vector<double>> fields;
  auto values = [&](const Jet* a) -> const double* {
    if (!a) return nullptr;
    fields.emplace_back(n);
    for (int i = 0; i < n; ++i) fields.back()[i] = a[i].a;
    return fields.back().data();
  };
  fields.reserve(kFields + 1);
  ClassState<double> sd;
  sd.n = n, sd.volume = s.volume, sd.diameter = s.diameter, sd.number = values(s.number);
  for (int f = 0; f < kFields; ++f) sd.fields[f] = values(s.fields[f]);
  fn_(sd, pv.data(), bv.data());
  for (size_t k = 0; k < bv.size(); ++k) beta[k] = Jet(bv[k]);
  // Parameters the Jet differentiates by (sensitivities, calibration): d beta / d p_k by a central difference of
  // relative step 1e-6 (absolute 1e-6 at p_k = 0), which the callable's double arithmetic allows; the step stays
  // inside the parameter's bounds by falling back to a one-sided difference at a bound.
  std::vector<double> hi(bv.size()), lo(bv.size());
  for (size_t k = 0; k < pv.size(); ++k) {
    if (p[k].v.isZero()) continue;
    const double x = pv[k], h = 1e-6 * (x != 0 ? std::abs(x) : 1.0);
    const double up = std::min(x + h, specs_[k].upper), down = std::max(x - h, specs_[k].lower);
    if (!(up > down)) continue;
    pv[k] = up;
    fn_(sd, pv.data(), hi.data());
    pv[k] = down;
    fn_(sd, pv.data(), lo.data());
    pv[k] = x;
    for (size_t q = 0; q < bv.size(); ++q) beta[q].v += (hi[q] - lo[q]) / (up - down) * p[k].v;
  }
}

void register_callback_kernel(Registry<AggregationKernel>& r, const std::string& name, const std::string& description,
                              std::vector<ParamSpec> params, ClassNeeds needs, BetaCallback fn) {
  r.add(name, description + " (callable, prototyping)",
        [params, needs, fn] { return std::make_unique<CallbackKernel>(params, needs, fn); });
}

}  // namespace granuflow::kernels
