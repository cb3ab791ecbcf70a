// GRANUFLOW_ISA is the target property of the library this file is compiled into (framework/CMakeLists.txt): the
// baseline copy and each instruction-set copy of the framework report their own.
#include "granuflow/build_info.hpp"

#include <link.h>

#include <cstring>

namespace granuflow {

const char* build_isa() { return GRANUFLOW_ISA; }

std::vector<std::string> loaded_core_libraries() {
  std::vector<std::string> out;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        const char* name = info->dlpi_name ? info->dlpi_name : "";
        const char* slash = std::strrchr(name, '/');
        if (std::strncmp(slash ? slash + 1 : name, "libgranuflow_", 13) == 0)
          static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &out);
  return out;
}

}  // namespace granuflow
