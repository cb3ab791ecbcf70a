// Registration by name, explicit and deterministic: each plugin file exports register_<name>(Registry&), and one
// list per family (units/registry.cpp, kernels/registry.cpp) calls them; libraries loaded at run time add theirs
// after the built-in ones (granuflow/plugin.hpp). Registering a name twice is an error;
// create() of an unknown name throws ConfigError listing the valid names.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "granuflow/errors.hpp"

namespace granuflow {

// The plugin file whose registration is running, "" outside of one (framework/src/plugins.cpp).
const std::string& registering_plugin();

template <class Base>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Base>()>;
  struct Entry {
    std::string description;
    Factory make;
    std::string origin;  // the plugin file that registered it, "" for built-in code (granuflow/plugin.hpp)
  };

  explicit Registry(std::string family) : family_(std::move(family)) {}

  void add(const std::string& name, std::string description, Factory make) {
    if (entries_.count(name)) throw std::logic_error(family_ + " '" + name + "' is registered twice");
    entries_.emplace(name, Entry{std::move(description), std::move(make), registering_plugin()});
  }

  std::unique_ptr<Base> create(const std::string& name, const std::string& where = "") const {
    auto it = entries_.find(name);
    if (it == entries_.end())
      throw ConfigError((where.empty() ? "" : where + ": ") + "unknown " + family_ + " '" + name +
                        "' (allowed: " + joined_names() + ")");
    return it->second.make();
  }

  bool contains(const std::string& name) const { return entries_.count(name) > 0; }
  const std::string& description(const std::string& name) const { return entries_.at(name).description; }
  const std::string& origin(const std::string& name) const { return entries_.at(name).origin; }

  std::vector<std::string> names() const {
    std::vector<std::string> v;
    for (const auto& [k, e] : entries_) v.push_back(k);
    return v;
  }

  std::string joined_names() const {
    std::string s;
    for (const auto& [k, e] : entries_) s += (s.empty() ? "" : ", ") + k;
    return s;
  }

 private:
  std::string family_;
  std::map<std::string, Entry> entries_;
};

}  // namespace granuflow
