// granuflow::splice_settings (scene.hpp): changing unit settings in a scene's text while keeping everything else byte
// for byte. yaml-cpp reports where a node starts; where a scalar ends is read from the text here.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"

namespace granuflow {
namespace {

struct Edit {
  size_t start, end;
  std::string text;
};

[[noreturn]] void cannot(const std::string& label, const std::string& why) {
  throw ConfigError(label + ": cannot change the settings of this scene text (" + why + ")");
}

YAML::Node child(const YAML::Node& map, const std::string& key) {
  if (!map || !map.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  for (const auto& kv : map)
    if (kv.first.IsScalar() && kv.first.Scalar() == key) return kv.second;
  return YAML::Node(YAML::NodeType::Undefined);
}

// Where the scalar starting at `pos` ends (one past its last character), its properties (tag, anchor) included, as
// PyYAML's end mark puts it. `flow`: inside a flow collection, where , ] } end a plain scalar.
size_t scalar_end(const std::string& t, size_t pos, bool flow, const std::string& value, const std::string& label) {
  while (pos < t.size() && (t[pos] == '!' || t[pos] == '&')) {  // a property, then a space
    while (pos < t.size() && t[pos] != ' ' && t[pos] != '\t' && t[pos] != '\n') ++pos;
    while (pos < t.size() && (t[pos] == ' ' || t[pos] == '\t')) ++pos;
  }
  if (pos >= t.size()) return pos;
  if (t[pos] == '"') {
    for (size_t k = pos + 1; k < t.size(); ++k) {
      if (t[k] == '\\')
        ++k;
      else if (t[k] == '"')
        return k + 1;
    }
    cannot(label, "an unclosed double-quoted value");
  }
  if (t[pos] == '\'') {
    for (size_t k = pos + 1; k < t.size(); ++k) {
      if (t[k] != '\'') continue;
      if (k + 1 < t.size() && t[k + 1] == '\'') {
        ++k;
        continue;
      }
      return k + 1;
    }
    cannot(label, "an unclosed single-quoted value");
  }
  if (t[pos] == '|' || t[pos] == '>') cannot(label, "a setting written as a block scalar");
  size_t end = pos;
  while (end < t.size() && t[end] != '\n' && t[end] != '\r') {
    if ((t[end] == '#' && end > pos && (t[end - 1] == ' ' || t[end - 1] == '\t')) ||
        (flow && (t[end] == ',' || t[end] == ']' || t[end] == '}')))
      break;
    ++end;
  }
  while (end > pos && (t[end - 1] == ' ' || t[end - 1] == '\t')) --end;
  if (t.compare(pos, end - pos, value) != 0) cannot(label, "a setting written over several lines");
  return end;
}

// Adding the entries ("a: 1", "b: 2") to the mapping `node`: an empty {} is replaced as a whole; a flow mapping gets
// them in front of its first key; a block mapping one per line at its keys' indentation. An entry is never split: it
// may itself be a flow mapping ("settings: {a: 1, b: 2}", which on two lines at the keys' indentation would not be
// YAML) or a value with a comma in it.
Edit insertion(const std::string& t, const YAML::Node& node, const std::vector<std::string>& entries) {
  auto joined = [&](const std::string& sep) {
    std::string s;
    for (const auto& e : entries) s += (s.empty() ? "" : sep) + e;
    return s;
  };
  if (node.size() == 0) {
    const size_t start = static_cast<size_t>(node.Mark().pos);
    const size_t close = t.find('}', start);
    return {start, close == std::string::npos ? start : close + 1, "{" + joined(", ") + "}"};
  }
  const YAML::Mark first = node.begin()->first.Mark();
  const auto at = static_cast<size_t>(first.pos);
  if (node.Style() == YAML::EmitterStyle::Flow) return {at, at, joined(", ") + ", "};
  const std::string indent(static_cast<size_t>(first.column), ' ');
  return {at, at, joined("\n" + indent) + "\n" + indent};
}

}  // namespace

std::string splice_settings(const std::string& text, const std::string& unit,
                            const std::vector<std::pair<std::string, std::string>>& settings,
                            const std::string& label) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    cannot(label, e.what());
  }
  YAML::Node section = unit == "particles" ? child(root, "particles") : YAML::Node(YAML::NodeType::Undefined);
  if (!section.IsDefined()) section = child(child(root, "units"), unit);
  if (!section.IsMap()) throw ConfigError(label + ": no unit '" + unit + "' with a mapping in the scene text");
  std::vector<Edit> edits;
  const YAML::Node node = child(section, "settings");
  if (!node.IsMap()) {
    std::string all;
    for (const auto& [k, v] : settings) all += (all.empty() ? "" : ", ") + k + ": " + v;
    edits.push_back(insertion(text, section, {"settings: {" + all + "}"}));
  } else {
    std::vector<std::string> missing;
    const bool flow = node.Style() == YAML::EmitterStyle::Flow;
    for (const auto& [k, v] : settings) {
      const YAML::Node value = child(node, k);
      if (value.IsDefined() && value.IsScalar()) {
        const auto start = static_cast<size_t>(value.Mark().pos);
        edits.push_back({start, scalar_end(text, start, flow, value.Scalar(), label), v});
      } else {
        missing.push_back(k + ": " + v);
      }
    }
    if (!missing.empty()) edits.push_back(insertion(text, node, missing));
  }
  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) {
    return std::tie(a.start, a.end, a.text) > std::tie(b.start, b.end, b.text);
  });
  std::string out = text;
  for (const auto& e : edits) out.replace(e.start, e.end - e.start, e.text);
  return out;
}

}  // namespace granuflow
