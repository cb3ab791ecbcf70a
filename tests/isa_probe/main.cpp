// Prints, one per line, what each library of the probe was built for, the Eigen alignment of the upper one and the
// files the loader chose for them; with a plugin's path as argument, what the plugin sees of the upper library
// (tests/python/test_isa_variants.py).
#include <dlfcn.h>
#include <link.h>

#include <cstdio>
#include <cstring>
#include <string>

std::string probe_top_base_isa();
std::string probe_top_isa();
int probe_top_vector4d_alignment();

int main(int argc, char** argv) {
  std::printf("top %s\nbase %s\nalign %d\n", probe_top_isa().c_str(), probe_top_base_isa().c_str(),
              probe_top_vector4d_alignment());
  // the plugin, installed beside the libraries (argv[1]: its path)
  void* plugin = argc > 1 ? dlopen(argv[1], RTLD_NOW | RTLD_LOCAL) : nullptr;
  auto sees = plugin ? reinterpret_cast<const char* (*)()>(dlsym(plugin, "probe_plugin_sees")) : nullptr;
  std::printf("plugin %s\n", sees ? sees() : dlerror());
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) {
        if (info->dlpi_name && std::strstr(info->dlpi_name, "libisa_probe_")) std::printf("file %s\n", info->dlpi_name);
        return 0;
      },
      nullptr);
  return 0;
}
