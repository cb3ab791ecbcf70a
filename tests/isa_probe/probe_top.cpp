// The upper library of the probe (CMakeLists.txt): its own instruction set, and the alignment of a fixed-size Eigen
// vector as this copy lays it out (the layout of AD numbers that granuflow's libraries, extension and plugins share).
#include <Eigen/Core>
#include <string>

std::string probe_base_isa();

std::string probe_top_isa() {
#if defined(__AVX2__) && defined(__FMA__)
  return std::string(PROBE_ISA) + " avx2+fma";
#else
  return std::string(PROBE_ISA) + " baseline";
#endif
}

std::string probe_top_base_isa() { return probe_base_isa(); }

int probe_top_vector4d_alignment() { return alignof(Eigen::Vector4d); }
