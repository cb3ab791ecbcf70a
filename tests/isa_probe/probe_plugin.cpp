// A module built once, for the baseline, against the upper library, as a plugin is built against an installed
// granuflow: loaded at run time, it reaches whichever copy of the upper library the process runs.
#include <string>

std::string probe_top_isa();

extern "C" const char* probe_plugin_sees() {
  static const std::string seen = probe_top_isa();
  return seen.c_str();
}
