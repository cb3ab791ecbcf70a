#include "bed_layering.hpp"

#include <algorithm>

#include "granuflow/flowsheet.hpp"
#include "kernels/registry.hpp"

namespace granuflow::units {

void BedLayering::declare(Settings& st, const kernels::Grid& g) {
  const auto& reg = kernels::registries().growth_schemes;
  fv_ = reg.create(st.get_choice("layering_scheme", "fv_van_albada", reg.names(),
                                 "finite-volume scheme of the binder's layering (fv_van_albada: smooth, for the "
                                 "integrator)"),
                   st.where());
  fv_->setup(g);
  n_ = g.size();
  x_hi_ = g.upper_virtual();
}

// Paper 003, Eqs. (7.32)-(7.34): number fluxes F_f through the faces, normalized so that the created volume is
// m_s / rho; in mass, class i gains pm_i F_i and loses pm_i F_{i+1}, and what crosses the top face stays in the top
// class at the virtual pivot's volume, so the mass gained is exactly m_s. Water moves with the donor cell's particles.
template <class T>
void BedLayering::rates(const Classes<T>& k, const T& m_s, Scratch<T>& sc, T* dM, T* dW) const {
  sc.F.resize(n_ + 1), sc.donor.resize(n_ + 1);
  const T amount = m_s / k.rho;
  const kernels::GrowthTerms<T> g{1, k.shape, &amount, true};
  fv_->fluxes(k.N, g, sc.F.data(), sc.donor.data());
  for (int f = 0; f <= n_; ++f) {
    const T& F = sc.F[f];
    if (f > 0) dM[f - 1] -= k.pm[f - 1] * F;
    if (f < n_)
      dM[f] += k.pm[f] * F;
    else
      dM[n_ - 1] += k.rho * x_hi_ * F;
    const int d = sc.donor[f];
    if (d < 0 || f == n_) continue;  // water crossing the top face stays in the top class
    const T q = F * k.W[d] / (k.N[d] + k.floor[d]);
    if (f > 0) dW[f - 1] -= q;
    dW[f] += q;
  }
}

void BedLayering::jacobian(const Classes<double>& k, double m_s, Scratch<double>& sc, const Columns& cols,
                           JacobianSink& sink) const {
  // Along m_s (direction 0) and the shape at each face (1 + f), kAdChunk directions at a time.
  const int dirs = n_ + 2;
  std::vector<Jet> N(k.N, k.N + n_), W(k.W, k.W + n_), floor(k.floor, k.floor + n_), pm(k.pm, k.pm + n_),
      shape(k.shape, k.shape + n_ + 1), dM(n_), dW(n_);
  Scratch<Jet> sj;
  for (int first = 0; first < dirs; first += kAdChunk) {
    Jet ms(m_s);
    for (int f = 0; f <= n_; ++f) shape[f] = Jet(k.shape[f]);
    for (int d = first; d < std::min(dirs, first + kAdChunk); ++d) (d == 0 ? ms : shape[d - 1]).v[d - first] = 1.0;
    std::fill(dM.begin(), dM.end(), Jet(0.0)), std::fill(dW.begin(), dW.end(), Jet(0.0));
    rates(Classes<Jet>{N.data(), W.data(), floor.data(), pm.data(), shape.data(), Jet(k.rho)}, ms, sj, dM.data(),
          dW.data());
    for (int d = first; d < std::min(dirs, first + kAdChunk); ++d)
      for (int i = 0; i < n_; ++i)
        for (auto [row, v] :
             {std::pair{cols.m_row + i, dM[i].v[d - first]}, std::pair{cols.w_row + i, dW[i].v[d - first]}}) {
          if (v == 0.0) continue;
          if (d > 0)
            sink.add(row, cols.shape_cols[d - 1], -v);
          else
            for (const auto& [col, dms] : cols.amount_cols) sink.add(row, col, -v * dms);
        }
  }
  if (m_s == 0.0) return;  // nothing grows: no derivative along M and W
  const double amount = m_s / k.rho;
  const kernels::GrowthTerms<double> g{1, k.shape, &amount, true};
  sc.F.resize(n_ + 1), sc.donor.resize(n_ + 1), sc.dF.resize(size_t(n_ + 1) * n_);
  fv_->fluxes(k.N, g, sc.F.data(), sc.donor.data());
  fv_->flux_jacobian(k.N, g, sc.dF.data());
  // residual rows M_i' - rate: d rate / d M_l = sum_f c_if dF_f/dN_l / m_l, c_if the class's weight of face f
  for (int f = 0; f <= n_; ++f) {
    const double* dF = &sc.dF[size_t(f) * n_];
    for (int l = 0; l < n_; ++l) {
      if (dF[l] == 0.0) continue;
      const double v = dF[l] / k.pm[l];
      if (f > 0) sink.add(cols.m_row + f - 1, cols.m_col + l, k.pm[f - 1] * v);
      if (f < n_)
        sink.add(cols.m_row + f, cols.m_col + l, -k.pm[f] * v);
      else
        sink.add(cols.m_row + n_ - 1, cols.m_col + l, -k.rho * x_hi_ * v);
    }
    const int d = sc.donor[f];
    if (d < 0 || f == n_) continue;
    // water flux q = F pi_d, pi_d = W_d / (N_d + floor_d): from class f - 1 (if any) to class f
    const double den = k.N[d] + k.floor[d], pi = k.W[d] / den;
    auto water = [&](int col, double v) {
      if (f > 0) sink.add(cols.w_row + f - 1, col, v);
      sink.add(cols.w_row + f, col, -v);
    };
    for (int l = 0; l < n_; ++l) {
      double v = dF[l] * pi;
      if (l == d) v -= sc.F[f] * pi / den;
      if (v != 0.0) water(cols.m_col + l, v / k.pm[l]);
    }
    water(cols.w_col + d, sc.F[f] / den);
  }
}

template void BedLayering::rates(const Classes<double>&, const double&, Scratch<double>&, double*, double*) const;
template void BedLayering::rates(const Classes<Jet>&, const Jet&, Scratch<Jet>&, Jet*, Jet*) const;

}  // namespace granuflow::units
