#include "aggregation/callback.hpp"

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
}

void register_callback_kernel(Registry<AggregationKernel>& r, const std::string& name, const std::string& description,
                              std::vector<ParamSpec> params, ClassNeeds needs, BetaCallback fn) {
  r.add(name, description + " (callable, prototyping)",
        [params, needs, fn] { return std::make_unique<CallbackKernel>(params, needs, fn); });
}

}  // namespace granuflow::kernels
