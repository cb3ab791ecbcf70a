#include "mc_statistics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>

#include "granuflow/errors.hpp"
#include "mc_storage.hpp"

namespace granuflow::montecarlo {
namespace {

// mean, lower and upper bound of the 95 % interval of values[r * stride + offset], r over the replicas; entries that
// are undefined (NaN: a share before any droplet) are left out, and fewer than two defined ones give NaN.
void interval(const std::vector<double>& values, size_t stride, size_t offset, long replicas, double* mean, double* lo,
              double* hi) {
  double sum = 0.0;
  long n = 0;
  for (long r = 0; r < replicas; ++r) {
    const double v = values[static_cast<size_t>(r) * stride + offset];
    if (std::isfinite(v)) sum += v, ++n;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (n < 2) {
    *mean = n ? sum : nan, *lo = nan, *hi = nan;
    return;
  }
  const double m = sum / n;
  double ss = 0.0;
  for (long r = 0; r < replicas; ++r) {
    const double v = values[static_cast<size_t>(r) * stride + offset];
    if (std::isfinite(v)) ss += (v - m) * (v - m);
  }
  const double half = student_t975(n - 1) * std::sqrt(ss / (n - 1) / n);
  *mean = m, *lo = m - half, *hi = m + half;
}

}  // namespace

const std::vector<std::string>& quantity_names() {
  static const std::vector<std::string> names = {"number",
                                                 "m2",
                                                 "d_mean_over_d0",
                                                 "d50_over_d0",
                                                 "droplets_deposited",
                                                 "dried_unused_share",
                                                 "used_share",
                                                 "blocked_share",
                                                 "liquid_added",
                                                 "liquid_wet",
                                                 "liquid_bridges",
                                                 "liquid_blocked",
                                                 "liquid_residual",
                                                 "liquid_evaporated",
                                                 "liquid_imbibed"};
  return names;
}

double student_t975(long dof) {
  static const double table[30] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                   2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                                   2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) return std::numeric_limits<double>::quiet_NaN();
  if (dof <= 30) return table[dof - 1];
  const double z = 1.959963984540054, v = static_cast<double>(dof);  // Cornish-Fisher expansion beyond the table
  return z + (z * z * z + z) / (4.0 * v) + (5.0 * std::pow(z, 5) + 16.0 * z * z * z + 3.0 * z) / (96.0 * v * v);
}

Summary run(const Config& c, const std::vector<double>& times) {
  for (size_t k = 0; k < times.size(); ++k)
    if (!(times[k] >= 0.0) || !std::isfinite(times[k]) || (k && times[k] < times[k - 1]))
      throw ConfigError("monte_carlo output time " + fmt_num(times[k]) +
                        " s: output times must be finite, non-negative and ascending");
  const auto start = std::chrono::steady_clock::now();
  const long R = c.s.replicas;
  long threads = c.s.threads > 0 ? c.s.threads : static_cast<long>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::min(threads, R);
  std::vector<ReplicaResult> results(static_cast<size_t>(R));
  std::vector<std::exception_ptr> errors(static_cast<size_t>(threads));
  auto work = [&](long k) {
    try {
      for (long r = k; r < R; r += threads)
        results[static_cast<size_t>(r)] = run_replica(c, times, static_cast<uint64_t>(r));
    } catch (...) {
      errors[static_cast<size_t>(k)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (long k = 1; k < threads; ++k) pool.emplace_back(work, k);
  work(0);
  for (std::thread& th : pool) th.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);

  Summary s;
  s.times = times;
  s.replicas = R;
  s.threads = static_cast<int>(threads);
  const size_t nt = times.size(), nq = kQuantities;
  s.per_replica.resize(static_cast<size_t>(R) * nt * nq);
  std::vector<double> psd(static_cast<size_t>(R) * nt * kPsdBins);
  double wall = 0.0, bytes = 0.0, doublings = 0.0;
  for (long r = 0; r < R; ++r) {
    const ReplicaResult& x = results[static_cast<size_t>(r)];
    std::copy(x.series.begin(), x.series.end(), s.per_replica.begin() + static_cast<long>(r * nt * nq));
    std::copy(x.psd.begin(), x.psd.end(), psd.begin() + static_cast<long>(r * nt * kPsdBins));
    s.collisions += x.collisions, s.successes += x.successes, s.depositions += x.depositions;
    wall += x.wall_s, doublings += x.doublings;
    bytes = std::max(bytes, x.bytes / x.primaries);
  }
  s.events = s.collisions + s.depositions;
  s.events_per_s = wall > 0.0 ? s.events / wall : std::numeric_limits<double>::quiet_NaN();
  s.bytes_per_particle = bytes;
  s.bytes_per_agglomerate = Storage::kBytesPerAgglomerate;
  s.bytes_per_droplet = Storage::kBytesPerDroplet;
  s.doublings_mean = doublings / static_cast<double>(R);
  s.mean.resize(nt * nq), s.lo.resize(nt * nq), s.hi.resize(nt * nq);
  for (size_t k = 0; k < nt * nq; ++k) interval(s.per_replica, nt * nq, k, R, &s.mean[k], &s.lo[k], &s.hi[k]);
  s.psd_mean.resize(nt * kPsdBins), s.psd_lo.resize(nt * kPsdBins), s.psd_hi.resize(nt * kPsdBins);
  for (size_t k = 0; k < nt * kPsdBins; ++k)
    interval(psd, nt * kPsdBins, k, R, &s.psd_mean[k], &s.psd_lo[k], &s.psd_hi[k]);
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

}  // namespace granuflow::montecarlo
