// What this process runs of granuflow's core: the instruction set the loaded framework library was compiled for, and
// the files of the core libraries it loaded. An installed package may carry the core libraries twice, for the x86-64
// baseline and for x86-64-v3, and the dynamic loader picks the copy by the CPU (docs/install_and_plugins.md).
#pragma once
#include <string>
#include <vector>

namespace granuflow {

// "x86-64", "x86-64-v3", ... or "native" (a source build for the CPU it was built on).
const char* build_isa();

// Paths of the libgranuflow_* libraries loaded into this process, in loading order.
std::vector<std::string> loaded_core_libraries();

}  // namespace granuflow
