// Forward sensitivities by Jets carrying kAdChunk parameter directions: sensitivity residuals, quadrature rates,
// explicit states, initial values and reported outputs.
#include <algorithm>
#include <cmath>

#include "dae_internal.hpp"

namespace granuflow {

namespace {
// Directions [d0, d1) of jets[0, n) into out[d0, d1); false at the first that is not finite (the integrator then
// cuts its step).
bool take_directions(const std::vector<Jet>& jets, int n, size_t d0, size_t d1, double* const* out) {
  for (size_t d = d0; d < d1; ++d)
    for (int i = 0; i < n; ++i) {
      out[d][i] = jets[i].v[d - d0];
      if (!std::isfinite(out[d][i])) return false;
    }
  return true;
}
}  // namespace

// Seeds direction `slot` for parameter `id` and the parameters linked to it, where they belong to unit `u`.
// id < 0: a direction of the states alone (an event's rate along the trajectory, events_run.cpp).
void DaeSystem::seed(int id, int u, size_t slot, std::vector<Jet>& pj) const {
  if (id < 0) return;
  auto [pu, pk] = fs_.param_location(id);
  if (pu == u) pj[pk].v[slot] = 1.0;
  for (int t : fs_.linked_targets(id)) {
    auto [tu, tk] = fs_.param_location(t);
    if (tu == u) pj[tk].v[slot] = 1.0;
  }
}

// Loads directions [d0, d1) into the Jets: the first n_loaded states' values and sensitivities (y' ones zero
// without `ypS`), and every unit's parameters seeded with the directions of the parameters they are or follow.
void DaeSystem::load_directions(const double* y, const double* yp, const std::vector<int>& params, size_t d0, size_t d1,
                                const double* const* yS, const double* const* ypS, int n_loaded) {
  jets_plain_ = 0;
  for (int i = 0; i < n_loaded; ++i) {
    xj_[i] = Jet(y[i]);
    xdj_[i] = Jet(yp[i]);
    for (size_t d = d0; d < d1; ++d) {
      xj_[i].v[d - d0] = yS[d][i];
      if (ypS) xdj_[i].v[d - d0] = ypS[d][i];
    }
  }
  params_as_jets();
  // The same seeds as seed() for every unit, with each parameter's location and links looked up once: this runs at
  // every sensitivity residual, and per unit the look-ups cost more than the seeding.
  for (size_t d = d0; d < d1; ++d) {
    if (params[d] < 0) continue;
    const auto [pu, pk] = fs_.param_location(params[d]);
    pj_[pu][pk].v[d - d0] = 1.0;
    for (int t : fs_.linked_targets(params[d])) {
      const auto [tu, tk] = fs_.param_location(t);
      pj_[tu][tk].v[d - d0] = 1.0;
    }
  }
}

Status DaeSystem::sens_residual(double t, const double* y, const double* yp, const std::vector<int>& params,
                                const double* const* yS, const double* const* ypS, double* const* rS) {
  fill_params(t);
  const auto& units = fs_.units();
  rj_.assign(n_ext_, Jet(0.0));
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, ypS, n_);
    drive_states(xj_.data(), pj_);
    if (inline_) evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    drive_outputs(t, xj_.data(), xdj_.data(), pj_);
    for (size_t u = 0; u < units.size(); ++u) {
      if (inline_ && units[u].spec.is_explicit()) continue;
      const Status s = units[u].unit->residual(
          ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, rj_.data() + units[u].offset));
      if (s != Status::kOk) return s;
    }
    if (!take_directions(rj_, n_, d0, d1, rS)) return Status::kRecoverable;
  }
  return Status::kOk;
}

Status DaeSystem::quadrature_sens(double t, const double* y, const double* yp, const std::vector<int>& params,
                                  const double* const* yS, double* const* qdotS) {
  fill_params(t);
  const auto& units = fs_.units();
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_);
    drive_states(xj_.data(), pj_);
    if (inline_) evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    drive_outputs(t, xj_.data(), xdj_.data(), pj_);
    qj_.assign(n_quad_, Jet(0.0));
    for (size_t u = 0; u < units.size(); ++u)
      if (!units[u].spec.quadratures().empty())
        units[u].unit->quadrature(
            ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, qj_.data() + units[u].quad_offset));
    if (!take_directions(qj_, n_quad_, d0, d1, qdotS)) return Status::kRecoverable;
  }
  return Status::kOk;
}

void DaeSystem::extend_sensitivities(double t, const double* y, const double* yp, const std::vector<int>& params,
                                     const double* const* yS, double* const* yS_full) {
  for (size_t d = 0; d < params.size(); ++d) std::copy(yS[d], yS[d] + n_, yS_full[d]);
  if (!inline_) return;
  fill_params(t);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_);
    drive_states(xj_.data(), pj_);
    evaluate_explicit(t, xj_.data(), xdj_.data(), pj_, jet_scratch_);
    for (size_t d = d0; d < d1; ++d)
      for (int i = n_; i < n_ext_; ++i) yS_full[d][i] = xj_[i].v[d - d0];
  }
}

void DaeSystem::initial_sensitivities(const std::vector<int>& params, std::vector<std::vector<double>>& yS0) const {
  yS0.assign(params.size(), std::vector<double>(n_, 0.0));
  const auto& units = fs_.units();
  std::vector<std::vector<Jet>> pj(units.size());
  std::vector<Jet> x0(n_ext_);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    for (size_t u = 0; u < units.size(); ++u) {
      pj[u].resize(pvals_[u].size());
      for (size_t k = 0; k < pvals_[u].size(); ++k) pj[u][k] = Jet(pvals_[u][k]);
      for (size_t d = d0; d < d1; ++d) seed(params[d], static_cast<int>(u), d - d0, pj[u]);
    }
    for (size_t u = 0; u < units.size(); ++u) {
      InitCtx<Jet> c{pj[u].data(), x0.data() + units[u].offset};
      if (units[u].shared >= 0) c.shared = pj[units[u].shared].data();
      c.work = ws_[u].get();
      units[u].unit->initial(c);
    }
    for (size_t d = d0; d < d1; ++d)
      for (int i = 0; i < n_; ++i) yS0[d][i] = x0[i].v[d - d0];
  }
}

void DaeSystem::report_sensitivities(double t, const double* y, const double* yp, const double* q,
                                     const std::vector<int>& params, const double* const* yS, const double* const* qS,
                                     double* const* dout) {
  fill_params(t);
  const auto& units = fs_.units();
  const int no = fs_.n_outputs();
  std::vector<Jet> out(no);
  for (size_t d0 = 0; d0 < params.size(); d0 += kAdChunk) {
    const size_t d1 = std::min(params.size(), d0 + kAdChunk);
    load_directions(y, yp, params, d0, d1, yS, nullptr, n_ext_);
    drive_states(xj_.data(), pj_);
    drive_outputs(t, xj_.data(), xdj_.data(), pj_);
    for (int i = 0; i < n_quad_; ++i) {
      qj_[i] = Jet(q[i]);
      for (size_t d = d0; d < d1; ++d) qj_[i].v[d - d0] = qS ? qS[d][i] : 0.0;
    }
    std::fill(out.begin(), out.end(), Jet(0.0));
    int k = 0;
    for (size_t u = 0; u < units.size(); ++u) {
      const int nu = static_cast<int>(units[u].spec.outputs().size());
      if (nu == 0) continue;
      Ctx<Jet> c = ctx<Jet>(static_cast<int>(u), t, xj_.data(), xdj_.data(), pj_, out.data() + k);
      c.quad = qj_.data() + units[u].quad_offset;
      units[u].unit->report(c);
      const auto& quads = units[u].spec.quadratures();
      for (size_t j = 0; j < quads.size(); ++j) out[k + quads[j].output.i] = qj_[units[u].quad_offset + j];
      k += nu;
    }
    for (size_t d = d0; d < d1; ++d)
      for (int j = 0; j < no; ++j) dout[d][j] = out[j].v[d - d0];
  }
}

}  // namespace granuflow
