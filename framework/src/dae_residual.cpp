// Residual, quadrature rates and reported outputs at double precision, with inlined explicit units evaluated
// in dependency order first.
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "dae_internal.hpp"

namespace granuflow {

// Evaluates the explicit units in order: with their states set to zero, residual = -f.
template <class T>
void DaeSystem::evaluate_explicit(double t, T* x, T* xd, const std::vector<std::vector<T>>& params,
                                  std::vector<T>& scratch, const std::vector<int>* only) {
  const auto& units = fs_.units();
  // The explicit states have no derivatives: yp_ext_ holds their zeros from its construction (nothing else writes
  // them), other arrays get them here.
  bool zero_xd = true;
  if constexpr (std::is_same_v<T, double>) zero_xd = xd != yp_ext_.data();
  for (int u : only ? *only : explicit_order_) {
    const int ns = static_cast<int>(units[u].spec.states().size()), off = units[u].offset;
    std::fill(x + off, x + off + ns, T(0.0));  // x = 0: the residual x - f is then -f exactly
    if (zero_xd) std::fill(xd + off, xd + off + ns, T(0.0));
    scratch.resize(ns);
    units[u].unit->residual(ctx<T>(u, t, x, xd, params, scratch.data()));
    for (int k = 0; k < ns; ++k) x[off + k] = -scratch[k];
  }
}
template void DaeSystem::evaluate_explicit<double>(double, double*, double*, const std::vector<std::vector<double>>&,
                                                   std::vector<double>&, const std::vector<int>*);
template void DaeSystem::evaluate_explicit<Jet>(double, Jet*, Jet*, const std::vector<std::vector<Jet>>&,
                                                std::vector<Jet>&, const std::vector<int>*);

template <class T>
void DaeSystem::drive_states(const T* y, std::vector<std::vector<T>>& params, int sink) const {
  for (const auto& d : drives_)
    if (d.state >= 0 && (sink < 0 || d.unit == sink)) params[d.unit][d.param] = y[d.state];
}

// A measured output: the measured unit's outputs at (y, y'), its quadratures read as zero (resolve_drives refuses
// measuring one), its parameters with their drives by states.
template <class T>
void DaeSystem::drive_outputs(double t, const T* y, const T* yp, std::vector<std::vector<T>>& params, int sink) {
  if (!output_drives_) return;
  const auto& units = fs_.units();
  auto& out = per_scalar<T>(drive_out_, drive_out_j_);
  auto& quad = per_scalar<T>(drive_quad_, drive_quad_j_);
  quad.assign(n_quad_ + 1, T(0.0));
  for (const auto& d : drives_) {
    if (d.source_unit < 0 || (sink >= 0 && d.unit != sink)) continue;
    drive_states(y, params, d.source_unit);
    out.assign(units[d.source_unit].spec.outputs().size(), T(0.0));
    Ctx<T> c = ctx<T>(d.source_unit, t, y, yp, params, out.data());
    c.quad = quad.data() + units[d.source_unit].quad_offset;
    units[d.source_unit].unit->report(c);
    params[d.unit][d.param] = out[d.output];
  }
}
template void DaeSystem::drive_states<double>(const double*, std::vector<std::vector<double>>&, int) const;
template void DaeSystem::drive_states<Jet>(const Jet*, std::vector<std::vector<Jet>>&, int) const;
template void DaeSystem::drive_outputs<double>(double, const double*, const double*, std::vector<std::vector<double>>&,
                                               int);
template void DaeSystem::drive_outputs<Jet>(double, const Jet*, const Jet*, std::vector<std::vector<Jet>>&, int);

void DaeSystem::extend(double t, const double* y, const double* yp, double* y_full, double* yp_full) {
  std::copy(y, y + n_, y_full);
  std::copy(yp, yp + n_, yp_full);
  if (!inline_) return;
  fill_params(t);
  drive_states(y_full, pvals_);
  evaluate_explicit(t, y_full, yp_full, pvals_, scratch_);
}

Status DaeSystem::residual(double t, const double* y, const double* yp, double* r) {
  ++n_res_;
  fill_params(t);
  const auto& units = fs_.units();
  drive_states(y, pvals_);
  if (inline_) {
    std::copy(y, y + n_, y_ext_.begin());
    std::copy(yp, yp + n_, yp_ext_.begin());
    evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_);  // no allocation per residual
    y = y_ext_.data();
    yp = yp_ext_.data();
  }
  drive_outputs(t, y, yp, pvals_);
  for (size_t u = 0; u < units.size(); ++u) {
    if (inline_ && units[u].spec.is_explicit()) continue;
    const Status s = units[u].unit->residual(ctx<double>(static_cast<int>(u), t, y, yp, pvals_, r + units[u].offset));
    if (s != Status::kOk) return s;
  }
  for (int i = 0; i < n_; ++i)
    if (!std::isfinite(r[i])) return Status::kRecoverable;  // let the integrator cut the step, never pass NaN on
  return Status::kOk;
}

Status DaeSystem::quadrature(double t, const double* y, const double* yp, double* qdot) {
  fill_params(t);
  const auto& units = fs_.units();
  drive_states(y, pvals_);
  if (inline_) {
    std::copy(y, y + n_, y_ext_.begin());
    std::copy(yp, yp + n_, yp_ext_.begin());
    // a measured output may read any explicit state
    evaluate_explicit(t, y_ext_.data(), yp_ext_.data(), pvals_, scratch_, output_drives_ ? nullptr : &quad_explicit_);
    y = y_ext_.data();
    yp = yp_ext_.data();
  }
  drive_outputs(t, y, yp, pvals_);
  for (size_t u = 0; u < units.size(); ++u)
    if (!units[u].spec.quadratures().empty())
      units[u].unit->quadrature(ctx<double>(static_cast<int>(u), t, y, yp, pvals_, qdot + units[u].quad_offset));
  for (int i = 0; i < n_quad_; ++i)
    if (!std::isfinite(qdot[i])) return Status::kRecoverable;
  return Status::kOk;
}

void DaeSystem::report(double t, const double* y, const double* yp, const double* q, double* out) {
  fill_params(t);
  drive_states(y, pvals_);
  drive_outputs(t, y, yp, pvals_);
  const auto& units = fs_.units();
  int k = 0;
  for (size_t u = 0; u < units.size(); ++u) {
    const int no = static_cast<int>(units[u].spec.outputs().size());
    if (no == 0) continue;
    Ctx<double> c = ctx<double>(static_cast<int>(u), t, y, yp, pvals_, out + k);
    c.quad = q + units[u].quad_offset;
    units[u].unit->report(c);
    const auto& quads = units[u].spec.quadratures();
    for (size_t j = 0; j < quads.size(); ++j) out[k + quads[j].output.i] = q[units[u].quad_offset + j];
    k += no;
  }
}

}  // namespace granuflow
