// The process's allocator, set once when granuflow._core is imported (issue 32).
//
// Every solve hands its arrays to a Result: at 80 size classes the headline scene's states, derivatives and outputs
// at 121 times are 1.2 MB, at 20 classes 0.35 MB. glibc serves blocks above its mmap threshold (128 KiB at first,
// raised to the size of each such block freed) with fresh mappings, and gives the heap's top back to the kernel once
// more than twice that threshold is free. So each solve of a loop over simulate() faulted its arrays in page by page
// again, up to 320 faults per solve at 80 classes, and a fault costs 12-19 us on this project's virtual machines.
// With blocks up to 32 MiB (glibc's own ceiling for its moving threshold) taken from the heap, and the heap's free
// top returned only beyond 64 MiB, the next solve reuses the pages: 24.2 -> 18.8 ms at 80 classes (docs/design.md,
// "Speed and accuracy"). The price: a process keeps what it freed for reuse instead of returning it at once.
//
// The user's own choice wins: with any of glibc's MALLOC_*_ variables or a glibc.malloc tunable in the environment,
// or GRANUFLOW_MALLOC_TUNING=0, nothing is changed. Another value of GRANUFLOW_MALLOC_TUNING than 0 or 1 changes
// nothing either, and the import warns, naming it.
#include "allocator.hpp"

#include <cstdlib>
#include <cstring>
#include <string>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

extern char** environ;

namespace granuflow::python {

namespace {
constexpr int kMmapThreshold = 32 << 20;
constexpr int kTrimThreshold = 64 << 20;

bool glibc_configured() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.")) return true;
  for (char** e = environ; e && *e; ++e)
    if (std::strncmp(*e, "MALLOC_", 7) == 0 && std::strstr(*e, "_=")) return true;  // MALLOC_TRIM_THRESHOLD_=...
  return false;
}

bool tuned = false;
}  // namespace

std::string tune_allocator() {
  const char* own = std::getenv("GRANUFLOW_MALLOC_TUNING");
  const std::string choice = own ? own : "1";
  if (choice != "0" && choice != "1")
    return "GRANUFLOW_MALLOC_TUNING='" + choice +
           "': expected 0 (glibc's own malloc behaviour) or 1 (keep freed memory for the next solve, the default); "
           "glibc's behaviour is kept";
#if defined(__GLIBC__)
  if (choice == "1" && !glibc_configured())
    tuned = mallopt(M_MMAP_THRESHOLD, kMmapThreshold) == 1 && mallopt(M_TRIM_THRESHOLD, kTrimThreshold) == 1;
#endif
  return "";
}

bool allocator_tuned() { return tuned; }

}  // namespace granuflow::python
