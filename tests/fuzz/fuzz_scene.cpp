// libFuzzer target: the scene loader (load_scene_text) on arbitrary bytes. Contract: it returns a scene or
// throws ConfigError with one line that starts with the file's label; any other exception, a crash, a hang
// (-timeout), a sanitizer report or memory above -rss_limit_mb is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "granuflow/dae_system.hpp"
#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"
#include "units/registry.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace granuflow;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    Scene s = load_scene_text(text, "fuzz.yaml", units::builtin());
    DaeSystem sys(*s.flowsheet);  // configures every unit, as the first run does, with the accepted values
    clone_scene(s, units::builtin());
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    if (m.rfind("fuzz.yaml: ", 0) != 0 || m.find('\n') != std::string::npos || m.size() > 1500) {
      std::fprintf(stderr, "message breaks the contract (%zu chars): %s\n", m.size(), m.c_str());
      std::abort();
    }
  }
  return 0;
}
