// ParticleChamber's composition (particle_chamber.hpp): a particle system of several named solids, the mass of each
// per class, the first's as M_i minus the others'.
#include <algorithm>
#include <string>

#include "granuflow/flowsheet.hpp"
#include "particle_chamber.hpp"
#include "particle_chamber_work.hpp"

namespace granuflow::units {

// N_i = V_i / x_i with V_i = (M_i - sum_c Q_c,i) / rho_0 + sum_c Q_c,i / rho_c: a class's number follows its
// composition (the pivot masses pm serve only the floors).
template <class T>
void ParticleChamber::class_numbers(const Ctx<T>& c, const T*, T* N) const {
  const T* M = &c.x(sM_);
  const T rho0 = pp_.component_density(c.shared, 0);
  for (int i = 0; i < n_; ++i) N[i] = M[i] / rho0;
  for (int k = 1; k < K_; ++k) {
    const T* Q = &c.x(sQ_[k - 1]);
    const T dv = 1.0 / pp_.component_density(c.shared, k) - 1.0 / rho0;
    for (int i = 0; i < n_; ++i) N[i] += Q[i] * dv;
  }
  for (int i = 0; i < n_; ++i) N[i] /= grid_->pivot(i);
}

// Layering (paper 003, Eqs. (7.32)-(7.34)) of a composed population: the number fluxes F_f of the finite-volume
// scheme, normalized so that the created volume is `amount` = M_sus / rho_layer, change the volume of class i by
// x_i (F_i - F_{i+1}) (x_hi F_n kept in the top class); each component crosses face f with the particles of the donor
// cell d, F m_c,d / (N_d + floor_d) (water likewise); the sprayed component is deposited in each class with the
// volume the crossings leave unexplained, rho_layer (dV_i - sum_c t_c,i / rho_c), so that every class's
// composition fills its volume and the deposits sum to M_sus.
template <class T>
void ParticleChamber::composed_growth(const Ctx<T>& c, const T* N, const T* W, const T& amount, T* dM, T* dQ,
                                      T* dW) const {
  auto& sc = c.template ws<Work>().template scratch<T>();
  const kernels::GrowthTerms<T> g{1, sc.ones.data(), &amount, true};
  fv_->fluxes(N, g, sc.F.data(), sc.donor.data());
  const T* M = &c.x(sM_);
  T* dv = sc.dv.data();
  std::fill(dv, dv + n_, T(0.0));
  for (int f = 0; f <= n_; ++f) {
    const T& F = sc.F[f];
    if (f > 0) dv[f - 1] -= grid_->pivot(f - 1) * F;
    if (f < n_)
      dv[f] += grid_->pivot(f) * F;
    else
      dv[n_ - 1] += grid_->upper_virtual() * F;
    const int d = sc.donor[f];
    if (d < 0 || f == n_) continue;  // what crosses the top face stays in the top class
    const T per = F / (N[d] + sc.floor[d]);
    auto move = [&](const T& q, int k, T* rate) {  // mass flow q of component k (k < 0: water) from f - 1 to f
      if (f > 0) rate[f - 1] -= q;
      rate[f] += q;
      if (k < 0) return;
      if (k > 0) {
        T* r = dQ + (k - 1) * n_;
        if (f > 0) r[f - 1] -= q;
        r[f] += q;
      }
      const T vol = q / pp_.component_density(c.shared, k);
      if (f > 0) dv[f - 1] += vol;
      dv[f] -= vol;
    };
    T first = M[d];
    for (int k = 1; k < K_; ++k) {
      const T& q = c.x(sQ_[k - 1] + d);
      first -= q;
      move(T(per * q), k, dM);
    }
    move(T(per * first), 0, dM);
    if (W) move(T(per * W[d]), -1, dW);
  }
  const T rho = pp_.component_density(c.shared, layer_);
  for (int i = 0; i < n_; ++i) {
    const T dep = rho * dv[i];
    dM[i] += dep;
    if (layer_ > 0) dQ[(layer_ - 1) * n_ + i] += dep;
  }
}

// The engine moves number and each component's mass with the particles' volume; the first component's mass is the
// rest of the class's volume, rho_0 (x_i dN_i - sum_c dQ_c,i / rho_c), so that the class mass changes by
// rho_0 x_i dN_i + sum_c dQ_c,i (1 - rho_0 / rho_c).
template <class T>
void ParticleChamber::composed_engine(const Ctx<T>& c, const T* dN, const T* dq, T* dM, T* dQ) const {
  const T rho0 = pp_.component_density(c.shared, 0);
  for (int i = 0; i < n_; ++i) dM[i] += rho0 * grid_->pivot(i) * dN[i];
  for (int k = 1; k < K_; ++k) {
    const T f = 1.0 - rho0 / pp_.component_density(c.shared, k);
    for (int i = 0; i < n_; ++i) {
      const size_t j = size_t(k - 1) * n_ + i;
      dM[i] += dq[j] * f;
      dQ[j] += dq[j];
    }
  }
}

// Q_c,i' = (layering and engine rates) + inflows - outflows, from the workspace's arrays eval() filled.
template <class T>
void ParticleChamber::composed_residuals(const Ctx<T>& c) const {
  const auto& sc = c.template ws<Work>().template scratch<T>();
  for (int k = 1; k < K_; ++k)
    for (int i = 0; i < n_; ++i) {
      const size_t j = size_t(k - 1) * n_ + i;
      T out(0.0);
      for (int o = 0; o < kOutlets; ++o)
        if (outlet(o).rate) out += sc.oq[o][j];
      c.res(sQ_[k - 1] + i) = c.xd(sQ_[k - 1] + i) - (sc.dQ[j] + sc.in_q[j] - out);
    }
}

// Per component its hold-up (and balance) and its mass per class.
template <class T>
void ParticleChamber::composed_outputs(const Ctx<T>& c) const {
  const T* M = &c.x(sM_);
  T first_total(0.0);
  for (int i = 0; i < n_; ++i) {
    T first = M[i];
    for (int k = 1; k < K_; ++k) first -= c.x(sQ_[k - 1] + i);
    c.out(o_comp_class_[0] + i) = first;
    first_total += first;
  }
  c.out(o_comp_mass_[0]) = first_total;
  c.out(o_comp_hold_[0]) = first_total;
  for (int k = 1; k < K_; ++k) {
    T total(0.0);
    for (int i = 0; i < n_; ++i) {
      const T& q = c.x(sQ_[k - 1] + i);
      c.out(o_comp_class_[k] + i) = q;
      total += q;
    }
    c.out(o_comp_mass_[k]) = total;
    c.out(o_comp_hold_[k]) = total;
  }
}

template void ParticleChamber::class_numbers(const Ctx<double>&, const double*, double*) const;
template void ParticleChamber::class_numbers(const Ctx<Jet>&, const Jet*, Jet*) const;
template void ParticleChamber::composed_growth(const Ctx<double>&, const double*, const double*, const double&, double*,
                                               double*, double*) const;
template void ParticleChamber::composed_growth(const Ctx<Jet>&, const Jet*, const Jet*, const Jet&, Jet*, Jet*,
                                               Jet*) const;
template void ParticleChamber::composed_engine(const Ctx<double>&, const double*, const double*, double*,
                                               double*) const;
template void ParticleChamber::composed_engine(const Ctx<Jet>&, const Jet*, const Jet*, Jet*, Jet*) const;
template void ParticleChamber::composed_residuals(const Ctx<double>&) const;
template void ParticleChamber::composed_residuals(const Ctx<Jet>&) const;
template void ParticleChamber::composed_outputs(const Ctx<double>&) const;
template void ParticleChamber::composed_outputs(const Ctx<Jet>&) const;

}  // namespace granuflow::units
