// libFuzzer target: the reader of DEM collision-count files (parse_collision_counts, kernels/data_tables.hpp;
// format in docs/dem_collisions.md) and Eq. (12) of paper 002 on what it accepts (collision_frequency_table,
// kernels/aggregation/dem_collision.hpp), the path a user's CSV takes into the dem_collision kernel.
// Contract: the reader accepts, or throws ConfigError with one short printable line that starts with the file's
// name; what it accepts has n + 1 increasing finite edges, n class numbers and n x n counts, and gives a finite,
// non-negative, symmetric frequency table. Anything else is a finding.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "granuflow/errors.hpp"
#include "kernels/aggregation/dem_collision.hpp"
#include "kernels/data_tables.hpp"

namespace {

using namespace granuflow;

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "finding: %s\n", what.c_str());
  std::abort();
}

void check_message(const std::string& m, const std::string& path) {
  if (m.rfind(path + ": ", 0) != 0) finding("message does not start with the file's name: " + m);
  if (m.size() > 1500) finding("message of " + std::to_string(m.size()) + " chars");
  for (const unsigned char ch : m)
    if (ch < 0x20 || ch == 0x7f) finding("control character " + std::to_string(int(ch)) + " in the message");
}

void check_accepted(const kernels::CollisionCounts& c) {
  const int n = c.classes();
  if (n < 1 || c.edges.size() != size_t(n) + 1 || c.counts.size() != size_t(n) * n) finding("inconsistent sizes");
  if (!(c.dt > 0) || !std::isfinite(c.dt)) finding("window dt not positive and finite");
  for (int k = 0; k <= n; ++k)
    if (!std::isfinite(c.edges[k]) || (k > 0 && !(c.edges[k] > c.edges[k - 1]))) finding("edges not increasing");
  const kernels::Table t = kernels::collision_frequency_table(c);
  for (int i = 0; i < n; ++i) {
    if (c.class_of(0.5 * (c.edges[i] + c.edges[i + 1])) != i) finding("class_of misses its own class");
    for (int j = 0; j < n; ++j) {
      const double v = t.at(i, j);
      if (!std::isfinite(v) || v < 0) finding("frequency not finite and non-negative");
      if (v != t.at(j, i)) finding("frequency table not symmetric");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = "fuzz.csv";
  kernels::CollisionCounts c;
  try {
    c = kernels::parse_collision_counts(std::string(reinterpret_cast<const char*>(data), size), path);
  } catch (const ConfigError& e) {
    check_message(e.what(), path);
    return 0;
  }
  check_accepted(c);
  return 0;
}
