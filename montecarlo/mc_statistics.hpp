// Replicas of the Monte Carlo run in parallel and their statistics: the mean of every recorded quantity at every
// output time with its 95 % confidence interval over the replicas (Student's t), and the cost (events per second of
// one core, allocated bytes per particle). Replica i is seeded from (seed, i) and the replicas are combined in their
// order, so the result is the same for any number of threads.
#pragma once
#include <string>
#include <vector>

#include "mc_engine.hpp"
#include "mc_params.hpp"

namespace granuflow::montecarlo {

struct Summary {
  std::vector<double> times;
  long replicas = 0;
  // [output time][quantity] and [output time][bin]: mean and the 95 % interval's bounds.
  std::vector<double> mean, lo, hi, psd_mean, psd_lo, psd_hi;
  std::vector<double> per_replica;  // [replica][output time][quantity]
  double events = 0, collisions = 0, successes = 0, depositions = 0;
  double events_per_s = 0;        // per core: events over the replicas' summed wall times
  double bytes_per_particle = 0;  // allocation over the primaries followed (largest over the replicas)
  double bytes_per_agglomerate = 0, bytes_per_droplet = 0;  // the layout: one slot of each array
  double wall_s = 0;                                        // whole run
  double doublings_mean = 0;
  int threads = 1;
};

const std::vector<std::string>& quantity_names();

// Two-sided 95 % quantile of Student's t with dof degrees of freedom.
double student_t975(long dof);

Summary run(const Config& c, const std::vector<double>& times);

}  // namespace granuflow::montecarlo
