// Small helpers the pieces of the calibration (src/*.cpp) share: timing, a thread pool for experiments, number
// formatting for messages and the least-squares cost.
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <iomanip>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "granuflow/calibration.hpp"

namespace granuflow::calib {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Runs f(0..n-1) on up to `threads` threads; the first exception (by index) is rethrown.
template <class F>
void parallel_for(int n, int threads, F&& f) {
  threads = std::max(1, std::min(threads, n));
  std::vector<std::exception_ptr> errors(n);
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i; (i = next++) < n;) {
      try {
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

// What Observation and Experiment promise (calibration.hpp): the loss indexes values by times and divides by σ.
void validate_experiments(const std::vector<Experiment>& exps);

inline double half_sum_squares(const std::vector<double>& r) {
  double c = 0;
  for (double v : r) c += v * v;
  return 0.5 * c;
}

inline std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

}  // namespace granuflow::calib
