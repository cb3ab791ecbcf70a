// A kernel given as a callable returning the n x n matrix beta (1/s), for prototyping (e.g. from Python through
// the bindings). Slower than a compiled kernel: the callable runs in double only, so the Jet evaluation
// treats beta as constant in the state (exact only when needs().number is false) and differentiates it by its own
// parameters with central finite differences (callback.cpp), two more calls per parameter a sensitivity or a
// calibration asks for. State-independent callables are still evaluated once per run.
#pragma once
#include <algorithm>
#include <functional>
#include <string>

#include "aggregation/aggregation_kernel.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

using BetaCallback = std::function<void(const ClassState<double>& s, const double* p, double* beta)>;

class CallbackKernel : public AggregationKernel {
 public:
  CallbackKernel(std::vector<ParamSpec> specs, ClassNeeds needs, BetaCallback fn)
      : specs_(std::move(specs)), needs_(needs), fn_(std::move(fn)) {}
  std::vector<ParamSpec> params() const override { return specs_; }
  ClassNeeds needs() const override { return needs_; }
  void factor(const ClassState<double>& s, const double* p, double* beta) const override { fn_(s, p, beta); }
  void factor(const ClassState<Jet>& s, const Jet* p, Jet* beta) const override;
  void efficiencies(const double*, int n, const double*, double* E) const override {
    std::fill(E, E + size_t(n) * (n + 1) / 2, 1.0);
  }
  void efficiencies(const Jet*, int n, const Jet*, Jet* E) const override {
    std::fill(E, E + size_t(n) * (n + 1) / 2, Jet(1.0));
  }
  void efficiency_gradients(const double*, int n, const double*, int, double* E, double*, double*) const override {
    std::fill(E, E + size_t(n) * (n + 1) / 2, 1.0);  // no features: nothing to differentiate
  }

 private:
  std::vector<ParamSpec> specs_;
  ClassNeeds needs_;
  BetaCallback fn_;
};

// Registers `fn` under `name` (a duplicate name throws, as for every registration).
void register_callback_kernel(Registry<AggregationKernel>& r, const std::string& name, const std::string& description,
                              std::vector<ParamSpec> params, ClassNeeds needs, BetaCallback fn);

}  // namespace granuflow::kernels
