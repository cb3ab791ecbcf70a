// Vogel-Peukert selection rate of paper 001, Eq. (92) (Eqs. (90)-(91) combined):
//     K_break(d) = k' (1 - exp(-f_Mat E_m,min d (d / d_min,break - 1))),  0 below d_min,break,
// with d in the fit's size unit (setting <prefix>size_unit: um by default, mm; docs/paper001_decisions.md). The formula
// is kernels/breakage/paper001_breakage_laws.hpp's breakage_rate(); this wraps it as a registered kernel.
#pragma once
#include "breakage/paper001_breakage_laws.hpp"
#include "breakage/selection_rate.hpp"
#include "granuflow/registry.hpp"

namespace granuflow::kernels {

class VogelPeukertSelection : public PerClassRate<VogelPeukertSelection> {
 public:
  std::vector<ParamSpec> params() const override;
  void declare(Settings& s, const std::string& prefix) override;
  template <class T>
  T rate(const ClassState<T>& s, int i, const T* p) const {
    return paper001::breakage_rate(T(s.diameter[i]), unit_, p[0], p[1], p[2], p[3]);  // Eq. (92), paper 001
  }

 private:
  paper001::BreakageSizeUnit unit_ = paper001::BreakageSizeUnit::kMicrometre;
};

void register_vogel_peukert(Registry<SelectionRate>& r);

}  // namespace granuflow::kernels
