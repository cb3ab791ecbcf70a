// Deprecated spellings of renamed unit parameters (granuflow/renamed.hpp).
#include "granuflow/renamed.hpp"

#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <utility>

namespace granuflow {
namespace {
std::mutex mutex;
std::map<std::pair<std::string, std::string>, std::string>& table() {
  static std::map<std::pair<std::string, std::string>, std::string> t;
  return t;
}
}  // namespace

void add_renamed_param(const std::string& unit_type, const std::string& old_name, const std::string& new_name) {
  std::lock_guard<std::mutex> lock(mutex);
  table()[{unit_type, old_name}] = new_name;
}

std::string renamed_param(const std::string& unit_type, const std::string& old_name) {
  std::lock_guard<std::mutex> lock(mutex);
  const auto it = table().find({unit_type, old_name});
  return it == table().end() ? "" : it->second;
}

std::string use_renamed_param(const std::string& unit_type, const std::string& unit_name, const std::string& old_name) {
  const std::string renamed = renamed_param(unit_type, old_name);
  static std::set<std::pair<std::string, std::string>> warned;
  std::lock_guard<std::mutex> lock(mutex);
  if (!renamed.empty() && warned.insert({unit_type, old_name}).second)
    std::cerr << "granuflow: warning: parameter '" << unit_name << "." << old_name << "' is deprecated, it is now '"
              << unit_name << "." << renamed << "' (a kernel's parameter has one name in every unit)\n";
  return renamed;
}

}  // namespace granuflow
