// The plugin's one registration function: granuflow calls it once after loading the library, and everything it
// adds appears in `granuflow units`, `kernels`, `describe` and `docs` like the built-in models.
#include <granuflow/plugin.hpp>

void register_jacketed_tank();
void register_brownian_kernel();

namespace {
void register_example_models() {
  register_jacketed_tank();
  register_brownian_kernel();
}
}  // namespace

GRANUFLOW_PLUGIN(register_example_models)
