#include "mc_engine.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "mc_rng.hpp"
#include "mc_storage.hpp"

namespace granuflow::montecarlo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int32_t kNone = Storage::kNone;

// Liquid book-keeping of the sample, m3 (doubled with the sample).
struct Liquid {
  double added = 0, bridges = 0, blocked = 0, residual = 0, evaporated = 0, imbibed = 0;
  void scale(double f) { added *= f, bridges *= f, blocked *= f, residual *= f, evaporated *= f, imbibed *= f; }
};

class Replica {
 public:
  Replica(const Config& c, uint64_t index) : c_(c), p_(c.p), d_(c.d), rng_(c.s.seed, index) {
    np0_ = static_cast<uint32_t>(c.s.sample_size);
    st_.reset(np0_);
    primaries_ = np0_;
    physics_ = c.s.success == Success::kPhysics;
    free_area_ = kPi * p_.d0 * p_.d0;
  }

  ReplicaResult run(const std::vector<double>& times);

 private:
  // Height of a droplet of age tau: Eqs. (7.55) and (7.56) together (both lower it; paper 003, section 7.7.2).
  double height(double tau) const {
    return d_.k_imb > 0.0 ? d_.h0 - d_.k_dry * tau - d_.k_imb * std::sqrt(tau) : d_.h0 - d_.k_dry * tau;
  }
  double volume(double tau) const {
    const double r = height(tau) / d_.h0;
    return d_.V_drop * r * r * r;  // same contact angle: the cap's volume scales with h^3
  }
  bool wet(double tau) const { return tau < d_.t_life; }
  double collision_interval();
  double accessible_area(uint32_t n) const;
  int32_t pick_spot(uint32_t i, double t, double area);
  bool sticks(uint32_t i, uint32_t j, int32_t drop, double t) const;
  void lost(double tau, double* evaporated, double* imbibed) const;
  void finish(int32_t d, double tau, double Liquid::*where);
  int32_t block(uint32_t i, double p_block, double t);
  void collide(double t);
  void double_sample();
  [[noreturn]] void too_many(double t) const;
  void record(double t, double* row, double* psd);

  const Config& c_;
  const Params& p_;
  const Derived& d_;
  Rng rng_;
  Storage st_;
  Liquid liq_;
  uint32_t np0_;
  double primaries_;  // primaries in the sample, 2^D N_p,0
  bool physics_;
  double free_area_;  // surface of one primary
  int doublings_ = 0;
  double collisions_ = 0, successes_ = 0, depositions_ = 0;
  unsigned events_ = 0;                          // for the interrupt check, every 1024 events
  double used_ = 0, blocked_ = 0, expired_ = 0;  // droplet fates (doubled with the sample)
  std::vector<uint32_t> scratch_;
};

double Replica::collision_interval() {
  const double np = st_.size();
  double rate;
  if (np < 2.0) return kInf;
  if (c_.s.collisions == Collisions::kConstantKernel) {
    const double volume = primaries_ / p_.c0;            // the sample's volume grows with each doubling
    rate = p_.beta0 * np * (np - 1.0) / (2.0 * volume);  // every pair at beta0 / V
  } else if (c_.s.time_step == TimeStep::kLiteral) {
    rate = d_.f_coll;  // Eq. (7.49) read literally: one per 1/f_coll
  } else {
    rate = 0.5 * d_.f_coll * np;  // Eq. (7.49), f_coll per particle, two per collision
  }
  if (!(rate > 0.0)) return kInf;
  return c_.s.waiting == Waiting::kExponential ? rng_.exponential() / rate : 1.0 / rate;
}

// Accessible surface of an agglomerate of n primaries: each bond covers 1/K_max of the surface of both primaries it
// joins (paper 003, section 7.7.2: fractional surface coverage and K_max); a tree of n primaries has n - 1 bonds.
double Replica::accessible_area(uint32_t n) const {
  const double covered = 2.0 * (n - 1.0) / (p_.K_max * n);
  return n * free_area_ * std::max(0.0, 1.0 - covered);
}

// Where the collision touches agglomerate i: a droplet with the probability of its base area (Eqs. (7.53)-(7.54) at
// the current height) over the accessible surface, or a dry spot (kNone). Droplets no longer wet are dropped from
// the list on the way.
int32_t Replica::pick_spot(uint32_t i, double t, double area) {
  double u = rng_.uniform() * area;
  int32_t prev = kNone;
  for (int32_t d = st_.head(i); d != kNone;) {
    const int32_t nx = st_.next(d);
    const double tau = t - st_.t_dep(d);
    if (!wet(tau)) {
      (prev == kNone ? st_.head(i) : st_.next(prev)) = nx;
      finish(d, d_.t_life, &Liquid::residual);
      expired_ += 1.0;
      d = nx;
      continue;
    }
    const double h = height(tau);
    u -= d_.area_per_h2 * h * h;
    if (u < 0.0) return d;
    prev = d;
    d = nx;
  }
  return kNone;
}

// Stokes criterion, Eqs. (7.57)-(7.58), with the harmonic means of both partners' masses and diameters.
bool Replica::sticks(uint32_t i, uint32_t j, int32_t drop, double t) const {
  const double tau = t - st_.t_dep(drop);
  const double h = height(tau);
  if (!(h > p_.h_a)) return false;  // St* <= 0
  const double ni = st_.n(i), nj = st_.n(j);
  const double mass = 2.0 * d_.m0 * ni * nj / (ni + nj);
  const double di = agglomerate_diameter(p_, ni), dj = agglomerate_diameter(p_, nj);
  double length = 2.0 * di * dj / (di + dj);
  if (c_.s.stokes_length == StokesLength::kRadius) length *= 0.5;
  const double r = d_.h0 / h;
  const double mu = p_.mu_exponent > 0.0 ? p_.mu_l * std::pow(r * r * r, p_.mu_exponent) : p_.mu_l;
  const double st = 2.0 * mass * p_.u_coll / (3.0 * kPi * mu * length * length);  // Eq. (7.57)
  const double st_crit = (1.0 + 1.0 / p_.e) * std::log(h / p_.h_a);               // Eq. (7.58)
  return st < st_crit;
}

// Liquid a droplet of age tau has lost to the gas and to the pores: the integrals of Eqs. (7.55)-(7.56) over its
// volume 3 V0 h^2 / h0^3 dh, in s = sqrt(tau) (h = h0 - k_imb s - k_dry s^2 is a polynomial there).
void Replica::lost(double tau, double* evaporated, double* imbibed) const {
  const double s = std::sqrt(tau), h0 = d_.h0, ki = d_.k_imb, kd = d_.k_dry;
  const double c[5] = {h0 * h0, -2.0 * h0 * ki, ki * ki - 2.0 * h0 * kd, 2.0 * ki * kd, kd * kd};  // h^2 in s
  double int_ds = 0.0, int_2s_ds = 0.0, pw = s;
  for (int k = 0; k < 5; ++k) {
    int_ds += c[k] * pw / (k + 1);
    int_2s_ds += 2.0 * c[k] * pw * s / (k + 2);
    pw *= s;
  }
  const double f = 3.0 * d_.V_drop / (h0 * h0 * h0);
  *evaporated = f * kd * int_2s_ds;
  *imbibed = f * ki * int_ds;
}

void Replica::finish(int32_t d, double tau, double Liquid::*where) {
  double ev, im;
  lost(tau, &ev, &im);
  liq_.evaporated += ev;
  liq_.imbibed += im;
  liq_.*where += volume(tau);
  st_.free_droplet(d);
}

// The droplets of agglomerate i after it bonded: each wet one is blocked with probability p_block (the share of its
// accessible surface the new bond covers). Returns the head of the survivors' list.
int32_t Replica::block(uint32_t i, double p_block, double t) {
  int32_t head = kNone;
  for (int32_t d = st_.head(i); d != kNone;) {
    const int32_t nx = st_.next(d);
    const double tau = t - st_.t_dep(d);
    if (!wet(tau)) {
      finish(d, d_.t_life, &Liquid::residual);
      expired_ += 1.0;
    } else if (rng_.uniform() < p_block) {
      finish(d, tau, &Liquid::blocked);
      blocked_ += 1.0;
    } else {
      st_.next(d) = head;
      head = d;
    }
    d = nx;
  }
  return head;
}

void Replica::collide(double t) {
  collisions_ += 1.0;
  const uint32_t np = st_.size();
  const uint32_t i = rng_.below(np);
  uint32_t j = rng_.below(np - 1);
  if (j >= i) ++j;
  if (!physics_) {
    if (!(rng_.uniform() < p_.p_success)) return;
    st_.n(i) += st_.n(j);
    st_.remove(j);
    successes_ += 1.0;
    return;
  }
  const double area_i = accessible_area(st_.n(i)), area_j = accessible_area(st_.n(j));
  const int32_t di = pick_spot(i, t, area_i);
  const int32_t dj = pick_spot(j, t, area_j);
  int32_t used = kNone;
  if (di != kNone && sticks(i, j, di, t))
    used = di;
  else if (dj != kNone && sticks(i, j, dj, t))
    used = dj;
  if (used == kNone) return;  // dry contact or rebound
  // The bridge's droplet leaves its list; unlink it by a walk (lists are a few droplets long).
  const uint32_t owner = used == di ? i : j;
  if (st_.head(owner) == used) {
    st_.head(owner) = st_.next(used);
  } else {
    int32_t d = st_.head(owner);
    while (st_.next(d) != used) d = st_.next(d);
    st_.next(d) = st_.next(used);
  }
  finish(used, t - st_.t_dep(used), &Liquid::bridges);
  used_ += 1.0;
  const double bond = free_area_ / p_.K_max;
  int32_t head = block(i, std::min(1.0, bond / area_i), t);
  int32_t tail_j = block(j, std::min(1.0, bond / area_j), t);
  if (tail_j != kNone) {  // join the lists
    int32_t d = tail_j;
    while (st_.next(d) != kNone) d = st_.next(d);
    st_.next(d) = head;
    head = tail_j;
  }
  st_.head(i) = head;
  st_.head(j) = kNone;
  st_.n(i) += st_.n(j);
  st_.remove(j);
  successes_ += 1.0;
}

void Replica::too_many(double t) const {
  throw SolverError("monte_carlo: the sample holds " + fmt_num(static_cast<double>(st_.droplet_slots())) +
                        " droplets at t = " + fmt_num(t) + " s (" + fmt_num(primaries_) + " primaries after " +
                        std::to_string(doublings_) + " doublings), the limit max_droplets; droplets that never dry " +
                        "pile up: shorten t_end, lower sample_size, or raise max_droplets",
                    t, "monte_carlo", 0.0);
}

void Replica::double_sample() {
  st_.duplicate();
  primaries_ *= 2.0;
  liq_.scale(2.0);
  used_ *= 2.0, blocked_ *= 2.0, expired_ *= 2.0, depositions_ *= 2.0;
  ++doublings_;
}

void Replica::record(double t, double* row, double* psd) {
  const uint32_t np = st_.size();
  double m2 = 0.0, dsum = 0.0, wet_liquid = 0.0, ev = 0.0, im = 0.0;
  for (uint32_t k = 0; k < np; ++k) {
    const double n = st_.n(k);
    m2 += n * n;
    dsum += agglomerate_diameter(p_, n);
    psd[std::min(kPsdBins - 1, static_cast<int>(std::log2(n)))] += n / primaries_;
    // Drop the droplets no longer wet, in place (the order of a list decides which droplet a contact point hits, so
    // recording must not change it), and sum the others.
    int32_t prev = kNone;
    for (int32_t d = st_.head(k); d != kNone;) {
      const int32_t nx = st_.next(d);
      const double tau = t - st_.t_dep(d);
      if (!wet(tau)) {
        (prev == kNone ? st_.head(k) : st_.next(prev)) = nx;
        finish(d, d_.t_life, &Liquid::residual);
        expired_ += 1.0;
      } else {
        double e1, i1;
        lost(tau, &e1, &i1);
        ev += e1, im += i1, wet_liquid += volume(tau);
        prev = d;
      }
      d = nx;
    }
  }
  scratch_.assign(st_.primaries().begin(), st_.primaries().end());
  std::sort(scratch_.begin(), scratch_.end());
  double cum = 0.0, n50 = scratch_.empty() ? 1.0 : scratch_.back();
  for (uint32_t n : scratch_)
    if ((cum += n) >= 0.5 * primaries_) {
      n50 = n;
      break;
    }
  const double undefined = std::numeric_limits<double>::quiet_NaN();
  const double dep = depositions_;
  row[kNumber] = np / primaries_;
  row[kM2] = m2 / primaries_;
  row[kDMean] = dsum / np / p_.d0;
  row[kD50] = agglomerate_diameter(p_, n50) / p_.d0;
  row[kDeposited] = dep / primaries_;
  row[kDriedUnusedShare] = dep > 0 ? expired_ / dep : undefined;
  row[kUsedShare] = dep > 0 ? used_ / dep : undefined;
  row[kBlockedShare] = dep > 0 ? blocked_ / dep : undefined;
  row[kLiquidAdded] = liq_.added / primaries_;
  row[kLiquidWet] = wet_liquid / primaries_;
  row[kLiquidBridges] = liq_.bridges / primaries_;
  row[kLiquidBlocked] = liq_.blocked / primaries_;
  row[kLiquidResidual] = liq_.residual / primaries_;
  row[kLiquidEvaporated] = (liq_.evaporated + ev) / primaries_;
  row[kLiquidImbibed] = (liq_.imbibed + im) / primaries_;
}

ReplicaResult Replica::run(const std::vector<double>& times) {
  const auto start = std::chrono::steady_clock::now();
  ReplicaResult r;
  r.series.assign(times.size() * kQuantities, 0.0);
  r.psd.assign(times.size() * kPsdBins, 0.0);
  scratch_.reserve(np0_);
  const bool spray = physics_ && d_.gamma > 0.0;
  double t = 0.0;
  double t_coll = collision_interval();
  double t_drop = spray ? 1.0 / (d_.gamma * primaries_) : kInf;  // Eq. (7.52)
  size_t k = 0;
  while (k < times.size()) {
    const double t_next = std::min(t_coll, t_drop);
    for (; k < times.size() && times[k] < t_next; ++k)
      record(times[k], &r.series[k * kQuantities], &r.psd[k * kPsdBins]);
    if (k == times.size() || t_next == kInf) break;
    t = t_next;
    if ((++events_ & 1023u) == 0 && interrupt_requested()) throw Interrupted(t);
    if (t_drop <= t_coll) {
      if (st_.droplet_slots() >= static_cast<size_t>(c_.s.max_droplets)) too_many(t);
      st_.deposit(rng_.below(st_.size()), t);  // the wetted particle is chosen at random
      liq_.added += d_.V_drop;
      depositions_ += 1.0;
      t_drop = t + 1.0 / (d_.gamma * primaries_);  // Eq. (7.52), primaries_ = 2^N N_p,0
      continue;
    }
    const uint32_t before = st_.size();
    collide(t);
    if (st_.size() != before && st_.size() <= np0_ / 2) double_sample();
    t_coll = t + collision_interval();  // Eq. (7.50), at the sample's current state
  }
  for (; k < times.size(); ++k) record(times[k], &r.series[k * kQuantities], &r.psd[k * kPsdBins]);
  r.collisions = collisions_;
  r.successes = successes_;
  r.depositions = depositions_;
  r.doublings = doublings_;
  r.bytes = static_cast<double>(st_.bytes() + scratch_.capacity() * sizeof(uint32_t));
  r.primaries = primaries_;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

ReplicaResult run_replica(const Config& c, const std::vector<double>& times, uint64_t index) {
  Replica rep(c, index);
  return rep.run(times);
}

}  // namespace granuflow::montecarlo
