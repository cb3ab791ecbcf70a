// Prints, one per line, what each library of the probe was built for, the Eigen alignment of the upper one and the
// files the loader chose for them (tests/python/test_isa_variants.py).
#include <link.h>

#include <cstdio>
#include <cstring>
#include <string>

std::string probe_top_base_isa();
std::string probe_top_isa();
int probe_top_vector4d_alignment();

int main() {
  std::printf("top %s\nbase %s\nalign %d\n", probe_top_isa().c_str(), probe_top_base_isa().c_str(),
              probe_top_vector4d_alignment());
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) {
        if (info->dlpi_name && std::strstr(info->dlpi_name, "libisa_probe_")) std::printf("file %s\n", info->dlpi_name);
        return 0;
      },
      nullptr);
  return 0;
}
