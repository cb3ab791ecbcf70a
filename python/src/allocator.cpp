// The process's allocator, set once when granuflow._core is imported (issue 32).
//
// Every solve hands its arrays to a Result: at 80 size classes the headline scene's states, derivatives and outputs
// at 121 times are 1.2 MB, at 20 classes 0.35 MB. glibc serves blocks above its mmap threshold (128 KiB at first,
// raised to the size of each such block freed) with fresh mappings, and gives the heap's top back to the kernel once
// more than twice that threshold is free. So each solve of a notebook's or a sweep's loop faulted its arrays in
// page by page again: 55 faults per solve at 20 classes and 309 at 80, at about 19 us each on this project's
// virtual machines, a fifth of the solve. With blocks up to 32 MiB (glibc's own ceiling for its moving threshold)
// taken from the heap, and up to 64 MiB of freed heap kept, the next solve reuses the pages: 26.3 -> 21.0 ms at 80
// classes (perf stat, 100 solves; docs/design.md, "Speed and accuracy"). The price is that a process keeps up to 64 MiB it freed.
//
// The user's own choice wins: with any of glibc's MALLOC_*_ variables or a glibc.malloc tunable in the environment,
// or GRANUFLOW_MALLOC_TUNING=0, nothing is changed.
#include "allocator.hpp"

#include <cstdlib>
#include <cstring>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

extern char** environ;

namespace granuflow::python {

namespace {
constexpr int kMmapThreshold = 32 << 20;
constexpr int kTrimThreshold = 64 << 20;

bool user_chose_allocator() {
  const char* own = std::getenv("GRANUFLOW_MALLOC_TUNING");
  if (own && std::strcmp(own, "0") == 0) return true;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.")) return true;
  for (char** e = environ; e && *e; ++e)
    if (std::strncmp(*e, "MALLOC_", 7) == 0 && std::strstr(*e, "_=")) return true;  // MALLOC_TRIM_THRESHOLD_=...
  return false;
}

bool tuned = false;
}  // namespace

void tune_allocator() {
#if defined(__GLIBC__)
  if (user_chose_allocator()) return;
  tuned = mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 1 && mallopt(M_TRIM_THRESHOLD, kTrimThreshold) == 1;
#endif
}

bool allocator_tuned() { return tuned; }

}  // namespace granuflow::python
