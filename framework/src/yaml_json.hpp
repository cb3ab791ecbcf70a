// A parsed YAML node as JSON text, its scalars typed as PyYAML's SafeLoader types them (YAML 1.1: yes/no/on/off are
// booleans, 017 is octal, 1e3 without a dot stays text, 1:30 is sexagesimal). The Python layer reads the scene
// sections it interprets (plots, sweep, notes, accuracy, particles, inputs, events) through this, so that a run never
// imports PyYAML, and a value means the same whichever side reads it (tests/python/test_scene_sections.py holds the
// two to each other).
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace granuflow {

// Quoted scalars and scalars tagged !!str are strings; plain ones are resolved as PyYAML resolves them. Differences
// that JSON forces: a timestamp stays its text (PyYAML would build a date), mapping keys are their text, and inf and
// nan are written Infinity and NaN (Python's json reads them).
std::string yaml_json(const YAML::Node& node);

}  // namespace granuflow
