// Units and kernels from a shared library that granuflow loads at run time (docs/install_and_plugins.md): a scene's
// `plugins:` list or the folders and files of GRANUFLOW_PLUGIN_PATH. The library is built against an installed
// granuflow (find_package(granuflow), granuflow_add_plugin) and ends with
//
//   GRANUFLOW_PLUGIN(register_my_models)
//
// where `void register_my_models()` adds its entries to granuflow::units::registry() and
// granuflow::kernels::registries(), as the built-in lists do. The macro exports the registration function and the
// ABI tag below; the loader refuses a library whose tag differs from its own, and reports a file that is no shared
// library or lacks the two symbols, in one line each (ConfigError), without calling into it.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "granuflow/version.hpp"

#define GRANUFLOW_PLUGIN_STR2(x) #x
#define GRANUFLOW_PLUGIN_STR(x) GRANUFLOW_PLUGIN_STR2(x)
// What must agree between granuflow and a plugin: the version (class layouts and registries may change between any
// two), libstdc++'s std::string ABI, which every registration passes, and Eigen's alignment, which sets the layout of
// the automatic-differentiation numbers units and kernels exchange (16 bytes for the x86-64 baseline, 32 with AVX,
// 64 with AVX-512: a plugin compiled for another instruction set reads their derivatives at the wrong offset; the
// installed CMake package passes granuflow's -march to plugins). Defined by hand only to test the refusal.
#ifndef GRANUFLOW_PLUGIN_ABI_TAG
#define GRANUFLOW_PLUGIN_ABI_TAG \
  "granuflow " GRANUFLOW_VERSION " (libstdc++ cxx11 ABI " GRANUFLOW_PLUGIN_STR(_GLIBCXX_USE_CXX11_ABI) ", Eigen " \
      "alignment " GRANUFLOW_PLUGIN_STR(EIGEN_MAX_ALIGN_BYTES) " bytes)"
#endif

#define GRANUFLOW_PLUGIN(register_function)                                              \
  extern "C" __attribute__((visibility("default"))) const char* granuflow_plugin_abi() { \
    return GRANUFLOW_PLUGIN_ABI_TAG;                                                     \
  }                                                                                      \
  extern "C" __attribute__((visibility("default"))) void granuflow_plugin_register() { register_function(); }

namespace granuflow {

// This build's tag (the one plugins must carry).
const char* plugin_abi_tag();

// Loads one plugin file and runs its registration. A file already loaded (same real path) is not loaded again.
// Returns the real path. Throws ConfigError naming the file and what is wrong.
std::string load_plugin(const std::string& path);

// Every plugin of a search path (entries separated by ':'): a folder contributes its *.so files in name order, a file
// itself; empty entries are skipped. Returns the real paths loaded.
std::vector<std::string> load_plugin_path(const std::string& search_path);

// The real paths of the plugins loaded so far, in loading order.
std::vector<std::string> loaded_plugins();

// The plugin whose registration function is running ("" outside of one): registries record it as an entry's origin.
const std::string& registering_plugin();

}  // namespace granuflow
