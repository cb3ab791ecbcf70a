// Loading plugins (granuflow/plugin.hpp): dlopen, the ABI tag compared before anything of the library runs beyond
// its static initializers, then its registration function. A loaded library is never closed: the factories it
// registered point into it.
#include <dirent.h>
#include <dlfcn.h>
#include <sys/stat.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <mutex>
#include <stdexcept>

#include "granuflow/errors.hpp"
#include "granuflow/plugin.hpp"

namespace granuflow {
namespace {

std::mutex& plugin_mutex() {
  static std::mutex m;
  return m;
}
std::vector<std::string>& loaded() {
  static std::vector<std::string> v;
  return v;
}
std::string& current() {
  static std::string s;
  return s;
}

std::string real_path(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) throw ConfigError("plugin '" + path + "': no such file");
  if (!S_ISREG(st.st_mode)) throw ConfigError("plugin '" + path + "': not a regular file (expected a shared library)");
  char buf[PATH_MAX];
  if (!realpath(path.c_str(), buf)) throw ConfigError("plugin '" + path + "': cannot resolve its path");
  return buf;
}

// dlerror() names the file and the reason (not an ELF file, a missing library or symbol); one line of it.
std::string dl_reason() {
  const char* e = dlerror();
  std::string s = e ? e : "unknown reason";
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

}  // namespace

const char* plugin_abi_tag() { return GRANUFLOW_PLUGIN_ABI_TAG; }

const std::string& registering_plugin() { return current(); }

std::string load_plugin(const std::string& path) {
  const std::string real = real_path(path);
  std::lock_guard<std::mutex> lock(plugin_mutex());
  if (std::find(loaded().begin(), loaded().end(), real) != loaded().end()) return real;
  void* h = dlopen(real.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!h) throw ConfigError("plugin '" + path + "': cannot be loaded as a shared library: " + dl_reason());
  using AbiFn = const char* (*)();
  using RegisterFn = void (*)();
  auto abi = reinterpret_cast<AbiFn>(dlsym(h, "granuflow_plugin_abi"));
  auto reg = reinterpret_cast<RegisterFn>(dlsym(h, "granuflow_plugin_register"));
  if (!abi || !reg) {
    dlclose(h);
    throw ConfigError("plugin '" + path +
                      "': not a granuflow plugin (no granuflow_plugin_abi/granuflow_plugin_register; a plugin ends "
                      "with GRANUFLOW_PLUGIN(register_function) from granuflow/plugin.hpp)");
  }
  const std::string tag = abi();
  if (tag != plugin_abi_tag()) {
    dlclose(h);
    throw ConfigError("plugin '" + path + "': built against " + tag + ", this is " + plugin_abi_tag() +
                      "; rebuild it against this granuflow");
  }
  current() = real;
  try {
    reg();
  } catch (const std::exception& e) {  // e.g. a name registered twice; what it added before stays registered
    current().clear();
    loaded().push_back(real);
    throw ConfigError("plugin '" + path + "': its registration failed: " + e.what());
  }
  current().clear();
  loaded().push_back(real);
  return real;
}

std::vector<std::string> load_plugin_path(const std::string& search_path) {
  std::vector<std::string> files;
  size_t start = 0;
  while (start <= search_path.size()) {
    const size_t end = std::min(search_path.find(':', start), search_path.size());
    const std::string entry = search_path.substr(start, end - start);
    start = end + 1;
    if (entry.empty()) continue;
    struct stat st;
    if (stat(entry.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
      std::vector<std::string> in_dir;
      if (DIR* d = opendir(entry.c_str())) {
        while (const dirent* f = readdir(d)) {
          const std::string n = f->d_name;
          if (n.size() > 3 && n.compare(n.size() - 3, 3, ".so") == 0) in_dir.push_back(entry + "/" + n);
        }
        closedir(d);
      }
      std::sort(in_dir.begin(), in_dir.end());
      files.insert(files.end(), in_dir.begin(), in_dir.end());
    } else {
      files.push_back(entry);
    }
  }
  std::vector<std::string> real;
  for (const auto& f : files) real.push_back(load_plugin(f));
  return real;
}

std::vector<std::string> loaded_plugins() {
  std::lock_guard<std::mutex> lock(plugin_mutex());
  return loaded();
}

}  // namespace granuflow
