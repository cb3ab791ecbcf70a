// The lower library of the probe (CMakeLists.txt): the instruction set it was compiled for, and whether the compiler
// had AVX2 and FMA then.
#include <string>

std::string probe_base_isa() {
#if defined(__AVX2__) && defined(__FMA__)
  return std::string(PROBE_ISA) + " avx2+fma";
#else
  return std::string(PROBE_ISA) + " baseline";
#endif
}
