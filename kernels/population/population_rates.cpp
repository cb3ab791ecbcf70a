// The population engine's rates: the per-particle properties, each mechanism's rates into work rows (class rows,
// then the outside rows), folded, then added to the unit's. Aggregation's events are placed by its scheme
// (discretization/aggregation_scheme.hpp), breakage is in population_breakage.cpp.
#include <algorithm>
#include <type_traits>

#include "population/population_work.hpp"

namespace granuflow::kernels {

template <class T>
ClassState<T> Population::class_state(const State<T>& s) const {
  ClassState<T> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  cs.number = s.N;
  for (int f = 0; f < kFields; ++f) cs.fields[f] = s.fields[f];
  return cs;
}

template <class T>
bool Population::fresh_tables(const Work&, const T* p, int first, int count) const {
  return has_derivative(p, first, count);
}
template ClassState<double> Population::class_state<double>(const State<double>&) const;  // the local Jacobian's
template bool Population::fresh_tables<double>(const Work&, const double*, int, int) const;
template bool Population::fresh_tables<Jet>(const Work&, const Jet*, int, int) const;

void Population::rates(Work& w, const State<double>& s, const Rates<double>& r) const {
  const FlushDenormals ftz;
  refresh(w, s.p);
  rates_t(w, s, r, true);
}

void Population::rates(Work& w, const State<Jet>& s, const Rates<Jet>& r) const {
  std::vector<double>& v = w.jinv;  // parameter values without derivatives, for the cached tables
  int np = 0;
  for (int k : kernel_params_) np = std::max(np, k + 1);
  v.resize(np);
  for (int k : kernel_params_) v[k] = s.p[k].a;
  refresh(w, v.data());
  make_jets(w);
  rates_t(w, s, r, true);
}

// The rates of every mechanism into work rows (class rows, then the outside rows), folded, then added to `r`.
template <class T>
void Population::rates_t(Work& w, const State<T>& s, const Rates<T>& r, bool fold) const {
  const int n = n_, P = properties(), no = outside_rows();
  auto& sc = w.scratch<T>();
  const ClassState<T> cs = class_state(s);
  const T* N = s.N;
  sc.rows.assign(n + no, T(0.0));
  sc.dq.assign(size_t(P) * n, T(0.0));
  T* dN = sc.rows.data();
  T* out = dN + n;
  T* dq = sc.dq.data();
  sc.pi.resize(size_t(P) * n);
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) sc.pi[size_t(p) * n + i] = s.q[p][i] / (N[i] + (s.floor ? s.floor[i] : T(0.0)));
  const auto& x = grid_->pivots();
  if (agg_.kernel) aggregation_rates(w, s, cs, dN, dq, out);
  if (sel_.kernel) breakage_rates(w, s, cs, dN, dq, out);
  if (growth_.kernel) {
    const T W = growth_rates(w, s, dN, dq, out);
    if (r.grown) *r.grown += W;
  }
  if (fold && outside_ == Outside::kFold) {
    dN[0] += out[kOutVolumeBelow] / x[0];
    dN[n - 1] += out[kOutVolumeAbove] / x[n - 1];
    for (int p = 0; p < P; ++p) {
      dq[size_t(p) * n] += out[out_property_below(p)];
      dq[size_t(p) * n + n - 1] += out[out_property_above(p)];
    }
  }
  for (int i = 0; i < n; ++i) r.dN[i] += dN[i];
  for (int p = 0; p < P; ++p)
    for (int i = 0; i < n; ++i) r.dq[p][i] += dq[size_t(p) * n + i];
  if (r.outside)
    for (int k = 0; k < no; ++k) r.outside[k] += out[k];
}
template void Population::rates_t<double>(Work&, const State<double>&, const Rates<double>&, bool) const;
template void Population::rates_t<Jet>(Work&, const State<Jet>&, const Rates<Jet>&, bool) const;

// The kernel's part of the event rates, h K_jk per pair (cached per parameter values, or from the parameters' Jets
// when they carry derivatives) and the efficiencies E_jk of a kernel with per-class features; the scheme forms the
// events and places the aggregates.
template <class T>
void Population::aggregation_rates(Work& w, const State<T>& s, const ClassState<T>& cs, T* dN, T* dq, T* out) const {
  const int n = n_;
  auto& sc = w.scratch<T>();
  const T* Kh;
  if constexpr (std::is_same_v<T, double>) {
    Kh = w.Kh.data();
  } else if (fresh_tables(w, s.p, agg_.first, agg_.count)) {
    if (!same_parameters(w.kh_params, s.p, agg_.first, agg_.count)) {
      sc.K.resize(size_t(n) * n);
      agg_.kernel->factor(cs, s.p + agg_.first, sc.K.data());
      pack_pairs(sc.K, n, sc.Kh);
    }
    Kh = sc.Kh.data();
  } else {
    Kh = w.Kh_jet.data();
  }
  const int m = agg_.kernel->n_features();
  const T* E = nullptr;
  if (m > 0) {
    sc.phi.resize(size_t(n) * m);
    agg_.kernel->features(cs, s.p + agg_.first, sc.phi.data());
    sc.E.resize(pair_count(n));
    agg_.kernel->efficiencies(sc.phi.data(), n, s.p + agg_.first, sc.E.data());
    E = sc.E.data();
  }
  agg_scheme_->rates(*w.agg, AggregationArgs<T>{grid_.get(), n, properties(), s.N, sc.pi.data(), Kh, E, dN, dq, out});
}

template <class T>
GrowthTerms<T> Population::growth_terms(Work& w, const T* p) const {
  const int nf = n_ + 1, terms = growth_.kernel->terms();
  auto& sc = w.scratch<T>();
  sc.shape.resize(size_t(terms) * nf);
  sc.amount.resize(terms);
  growth_.kernel->evaluate(growth_scheme_->face_diameters().data(), nf, p + growth_.first, sc.shape.data(),
                           sc.amount.data());
  sc.F.resize(nf);
  sc.donor.resize(nf);
  return {terms, sc.shape.data(), sc.amount.data(), growth_.kernel->volume_normalized()};
}
template GrowthTerms<double> Population::growth_terms<double>(Work&, const double*) const;

// Growth by the finite-volume fluxes of the growth scheme; properties move with the donor cell's particles.
template <class T>
T Population::growth_rates(Work& w, const State<T>& s, T* dN, T* dq, T* out) const {
  const int n = n_, P = properties();
  auto& sc = w.scratch<T>();
  const T* N = s.N;
  const T* pi = sc.pi.data();
  const int nf = n + 1;
  const GrowthTerms<T> g = growth_terms(w, s.p);
  const T W = growth_scheme_->fluxes(N, g, sc.F.data(), sc.donor.data());
  // paper 003, Eqs. (7.32), (7.34): dN_i/dt = F_i - F_{i+1}; what crosses an end face leaves at its virtual pivot
  for (int f = 0; f < nf; ++f) {
    const T& F = sc.F[f];
    if (f > 0)
      dN[f - 1] -= F;
    else
      out[kOutVolumeBelow] -= F * grid_->lower_virtual();
    if (f < n)
      dN[f] += F;
    else
      out[kOutNumberAbove] += F, out[kOutVolumeAbove] += F * grid_->upper_virtual();
    const int d = sc.donor[f];
    if (d < 0) continue;
    for (int p = 0; p < P; ++p) {
      const T Fq = F * pi[size_t(p) * n + d];
      if (f > 0)
        dq[size_t(p) * n + f - 1] -= Fq;
      else
        out[out_property_below(p)] -= Fq;
      if (f < n)
        dq[size_t(p) * n + f] += Fq;
      else
        out[out_property_above(p)] += Fq;
    }
  }
  return W;
}

}  // namespace granuflow::kernels
