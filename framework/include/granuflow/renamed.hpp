// Old spellings of unit parameters that were renamed (a kernel's parameters carry one name in every unit: docs/
// scene_format.md). Flowsheet::param_id accepts an old spelling as a deprecated alias of the new name and warns once
// per process on stderr, naming the new name, so scenes, calibration files and sweeps written before keep working.
#pragma once

#include <string>

namespace granuflow {

// Parameter `old_name` of units of type `unit_type` is now `new_name`. Idempotent, thread-safe.
void add_renamed_param(const std::string& unit_type, const std::string& old_name, const std::string& new_name);
// The new name of `unit_type`'s parameter `old_name`, or "" when it was not renamed.
std::string renamed_param(const std::string& unit_type, const std::string& old_name);
// renamed_param, and the first time an old spelling is used in this process a warning on stderr naming unit
// `unit_name`'s new parameter.
std::string use_renamed_param(const std::string& unit_type, const std::string& unit_name, const std::string& old_name);

}  // namespace granuflow
