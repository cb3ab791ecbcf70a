// Scene files (YAML): units, connections, parameters, time-dependent inputs, solver options, outputs and the
// summary mapping. Every unknown key, wrong type, unknown unit or out-of-bound value is a ConfigError whose
// message names the file, the key path, the value and what is allowed. The file is only read.
//
//   scene: demo_tanks                 # name (required)
//   description: ...                  # optional text
//   t_end: 2000 s                     # required; "value unit" or a number in SI
//   output: {n: 201}                  # or {times: [0 s, 10 s, ...]}
//   solver: {rtol: 1e-6, atol: 1e-8, max_steps: 100000, linear_solver: auto}
//   particles: {material: maltodextrin_de21, settings: {classes: 10}, params: {rho_s: 1545 kg/m3}}
//                                     # material: a catalogue entry (materials.hpp, `granuflow materials`)
//   units:
//     tank1: {type: stirred_tank, settings: {...}, params: {mass: 100 kg, Q: 20 kW}}
//   connections: ["feed.out -> mixer.in1", ...]
//   inputs:
//     feed.T: {interp: step, times: [0 s, 100 s], values: [300 K, 350 K]}
//   links: {bed.T0: inlet.T}          # a parameter that follows another (initial state at inlet state)
//   summary: {T_gas_out_K: chamber.T}  # summary key -> state or reported output
//   plots: [...]                      # free-form, read by the Python layer
#pragma once
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "granuflow/flowsheet.hpp"
#include "granuflow/registry.hpp"
#include "granuflow/simulator.hpp"

namespace granuflow {

struct Scene {
  std::string path;
  std::string name;
  std::string description;
  std::string material;  // particles.material (materials.hpp), "" when the scene names none
  // Parameters the catalogue knows but the named material gives no value for and the scene does not set: they keep
  // the units' built-in (paper 001) values, and a run says so.
  std::vector<std::string> material_unsupplied;
  std::unique_ptr<Flowsheet> flowsheet;
  SimOptions options;
  std::map<std::string, std::string> summary;  // summary key -> "unit.state" or "unit.output"
  std::string extra_yaml;                      // the keys the C++ core does not interpret (plots, sweep), as YAML
  // The sections the Python layer reads (plots, sweep, notes, accuracy, particles, inputs, events) as JSON, their
  // values typed as PyYAML would type them (yaml_json.hpp): a run reads its scene without PyYAML.
  std::map<std::string, std::string> sections_json;
  std::string text;  // the scene file as read, so a scene can be cloned for threads
};

// An independent copy (own flowsheet) with the same current parameter values and inputs.
Scene clone_scene(const Scene& s, const Registry<Unit>& units);

Scene load_scene(const std::string& path, const Registry<Unit>& units);
Scene load_scene_text(const std::string& yaml_text, const std::string& label, const Registry<Unit>& units);

// What every YAML file of granuflow must pass before a parser builds it (load_scene_text applies it; the Python
// layer can for sweep, contour, calibration and experiment files through _core.check_yaml_text): at most 1 MiB,
// UTF-8 text without control bytes, one document, at most 200000 values once aliases are expanded, no alias
// inside the node it names, nesting at most 64 deep, only YAML's standard tags. Throws ConfigError
// "label: line L, column C: ..." naming the file as a `kind` ("scene", "sweep file" ...).
void check_yaml_text(const std::string& text, const std::string& label, const std::string& kind = "scene");

// `text` with the `settings:` mapping of `unit` (the `particles:` section, else `units.<unit>`) holding `settings`
// (key, value as YAML flow text, e.g. a JSON string or number), everything else byte for byte (comments, layout):
// keys replaced where the mapping has them as scalars, the others added in front of its first key (a missing
// mapping is added to the section). ConfigError naming `label` when the text does not parse, has no such unit, or
// holds the value as a block scalar. The grid check and the accuracy target build their grids this way, --set and
// with_settings their scenes (scene_splice.cpp).
std::string splice_settings(const std::string& text, const std::string& unit,
                            const std::vector<std::pair<std::string, std::string>>& settings, const std::string& label);

// Parses "60 degC", "0.5", "700 m3/h" for parameter `qualified` and converts to its SI unit. Throws
// ConfigError naming `where`.
double parse_param_value(const Flowsheet& fs, const std::string& qualified, const std::string& text,
                         const std::string& where);

}  // namespace granuflow
