// One replica of the constant-volume, event-driven Monte Carlo (paper 003, section 7.7.2; docs/monte_carlo.md):
// collisions between uniformly chosen pairs at the rate of Eqs. (7.48)-(7.50), droplet deposition at the time per
// droplet of Eqs. (7.51)-(7.52), droplet ageing by Eqs. (7.55)-(7.56), coalescence by Eqs. (7.57)-(7.58), and periodic
// doubling of the sample when half of its particles are gone. The replica records its state at the output times.
#pragma once
#include <cstdint>
#include <vector>

#include "mc_params.hpp"

namespace granuflow::montecarlo {

// Recorded quantities, per output time. Amounts are per primary particle of the sample (the sample's volume grows
// with every doubling, its primaries with it), liquids in m3 per primary.
enum Quantity {
  kNumber,            // agglomerates per primary, N / N0 (the zeroth moment)
  kM2,                // second moment in primaries, sum n^2 / N0
  kDMean,             // number-mean agglomerate diameter / d0
  kD50,               // mass-median agglomerate diameter / d0
  kDeposited,         // droplets deposited per primary
  kDriedUnusedShare,  // share of the deposited droplets that stopped being wet before a collision used them
  kUsedShare,         // share that formed a bridge
  kBlockedShare,      // share blocked by a coalescence (coordination)
  kLiquidAdded,
  kLiquidWet,       // in droplets still wet
  kLiquidBridges,   // in the droplets that formed bridges, at their use
  kLiquidBlocked,   // in blocked droplets, at their blocking
  kLiquidResidual,  // left in droplets when they stopped being wet
  kLiquidEvaporated,
  kLiquidImbibed,
  kQuantities
};
constexpr int kPsdBins = 24;  // mass fractions of agglomerates with n in [2^k, 2^(k+1)) primaries

struct ReplicaResult {
  std::vector<double> series;  // [output time][quantity]
  std::vector<double> psd;     // [output time][bin]
  double collisions = 0, successes = 0, depositions = 0, wall_s = 0;
  double bytes = 0;      // allocated bytes at the end
  double primaries = 0;  // primary particles in the sample at the end
  int doublings = 0;
};

ReplicaResult run_replica(const Config& c, const std::vector<double>& times, uint64_t index);

}  // namespace granuflow::montecarlo
