#include "two_point_scheme.hpp"

#include <mutex>

#include "kernels/registry.hpp"

namespace granuflow::test_scheme {

using kernels::kOutNumberAbove;
using kernels::kOutVolumeAbove;
using kernels::out_property_above;

std::atomic<int> TwoPointSplit::setups{0}, TwoPointSplit::refreshes{0};

void TwoPointSplit::register_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    kernels::registries().aggregation_schemes.add(kName, "test: two-point split keeping number and volume",
                                                  [] { return std::make_unique<TwoPointSplit>(); });
  });
}

// Kumar & Ramkrishna 1996, Eq. (9): a particle of volume v between pivots a < b is shared as 1 - nu at a and nu at b,
// nu = (v - a) / (b - a), which keeps its number (1) and its volume ((1 - nu) a + nu b = v).
void TwoPointSplit::setup(const kernels::Grid& g) {
  ++setups;
  const int n = g.size();
  const double x_top = g.upper_virtual();
  dest_.clear();
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k) {
      Destination d{};
      d.v = g.pivot(j) + g.pivot(k);
      if (d.v >= x_top) {
        d.share[0] = {-1, 1.0, d.v}, d.count = 1;
      } else {
        int lo = k;  // the pivot nearest below v: at least x_k, since v > x_k
        while (lo + 1 < n && g.pivot(lo + 1) <= d.v) ++lo;
        const double a = g.pivot(lo), b = lo + 1 < n ? g.pivot(lo + 1) : x_top;
        const double nu = (d.v - a) / (b - a);
        d.share[0] = {lo, 1.0 - nu, (1.0 - nu) * a};
        d.share[1] = {lo + 1 < n ? lo + 1 : -1, nu, nu * b};
        d.count = 2;
      }
      dest_.push_back(d);
    }
}

// Nothing of the scheme depends on the kernel's values (it reads h K_jk from the engine); it only counts.
std::unique_ptr<kernels::AggregationScheme::Tables> TwoPointSplit::make_tables() const {
  return std::make_unique<Tables>();
}
void TwoPointSplit::refresh(Tables&, const kernels::AggregationTableInputs&) const { ++refreshes; }

template <class T>
void TwoPointSplit::rates_t(const kernels::AggregationArgs<T>& a) const {
  const int n = a.n, P = a.P;
  size_t pr = 0;
  for (int j = 0; j < n; ++j)
    for (int k = j; k < n; ++k, ++pr) {
      const T rate = (a.E ? a.Kh[pr] * a.E[pr] : a.Kh[pr]) * a.N[j] * a.N[k];
      a.dN[j] -= rate, a.dN[k] -= rate;
      for (int p = 0; p < P; ++p)
        a.dq[size_t(p) * n + j] -= rate * a.pi[size_t(p) * n + j],
            a.dq[size_t(p) * n + k] -= rate * a.pi[size_t(p) * n + k];
      const Destination& d = dest_[pr];
      for (int s = 0; s < d.count; ++s) {
        const Share& sh = d.share[s];
        const double f = sh.volume / d.v;  // the share of the partners' properties
        if (sh.cls >= 0) {
          a.dN[sh.cls] += sh.number * rate;
        } else {
          a.out[kOutNumberAbove] += sh.number * rate;
          a.out[kOutVolumeAbove] += sh.volume * rate;
        }
        for (int p = 0; p < P; ++p) {
          const T carried = f * rate * (a.pi[size_t(p) * n + j] + a.pi[size_t(p) * n + k]);
          if (sh.cls >= 0)
            a.dq[size_t(p) * n + sh.cls] += carried;
          else
            a.out[out_property_above(p)] += carried;
        }
      }
    }
}

void TwoPointSplit::rates(Tables&, const kernels::AggregationArgs<double>& a) const { rates_t(a); }
void TwoPointSplit::rates(Tables&, const kernels::AggregationArgs<Jet>& a) const { rates_t(a); }

void TwoPointSplit::jacobian_row(Tables&, const kernels::PopulationJacobian& J, const kernels::PairEvent* events,
                                 int count) const {
  for (int i = 0; i < count; ++i) {
    J.deaths(events[i]);
    births_jacobian(J, events[i]);
  }
}

// The births are linear in the event rate (number and volume shares) and in rate times the partners' properties.
void TwoPointSplit::births_jacobian(const kernels::PopulationJacobian& J, const kernels::PairEvent& e) const {
  const int n = J.n, P = J.P;
  const Destination& d = dest_[e.pr];
  for (int s = 0; s < d.count; ++s) {
    const Share& sh = d.share[s];
    const double f = sh.volume / d.v;
    for (const auto* in = e.begin; in != e.end; ++in) {
      if (sh.cls >= 0) {
        J.add(J.rowN(sh.cls), in->col, sh.number * in->d);
      } else {
        J.add(J.rowO(kOutNumberAbove), in->col, sh.number * in->d);
        J.add(J.rowO(kOutVolumeAbove), in->col, sh.volume * in->d);
      }
    }
    for (int p = 0; p < P; ++p) {
      const size_t row = sh.cls >= 0 ? J.rowQ(p, sh.cls) : J.rowO(out_property_above(p));
      const double carried = J.pi[size_t(p) * n + e.j] + J.pi[size_t(p) * n + e.k];
      for (const auto* in = e.begin; in != e.end; ++in) J.add(row, in->col, f * carried * in->d);
      for (int i : {e.j, e.k}) {
        J.add(row, i, f * e.rate * J.dpi_dN[size_t(p) * n + i]);
        J.add(row, J.colQ(p, i), f * e.rate * J.dpi_dq[size_t(p) * n + i]);
      }
    }
  }
}

}  // namespace granuflow::test_scheme
