#include "yaml_text.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "granuflow/errors.hpp"
#include "granuflow/scene.hpp"

namespace granuflow {
namespace {

// YAML aliases can make a few hundred bytes stand for 10^9 values, so nodes are counted with aliases expanded before
// anything walks the tree.
constexpr uint64_t kMaxNodes = 200000;
constexpr int kMaxDepth = 64;

}  // namespace

std::string shown(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (out.size() >= 60) return out + "...";
    if (c == '\n')
      out += "\\n";
    else if (c < 0x20 || c == 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", c);
      out += b;
    } else
      out += static_cast<char>(c);
  }
  return out;
}

namespace {

// Line and column (1-based) of byte `pos` of `text`.
std::string position(const std::string& text, size_t pos) {
  size_t line = 1, col = 1;
  for (size_t i = 0; i < pos && i < text.size(); ++i) {
    if (text[i] == '\n')
      ++line, col = 1;
    else
      ++col;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(col);
}

// The offset of the first byte that is not part of well-formed UTF-8 (RFC 3629: no overlong forms, no
// surrogates, at most U+10FFFF), or npos.
size_t invalid_utf8(const std::string& s) {
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  for (size_t i = 0; i < n;) {
    const unsigned c = b[i];
    size_t len;
    unsigned lo = 0x80, hi = 0xbf;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xc2 && c <= 0xdf) {
      len = 2;
    } else if (c >= 0xe0 && c <= 0xef) {
      len = 3;
      if (c == 0xe0) lo = 0xa0;
      if (c == 0xed) hi = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      len = 4;
      if (c == 0xf0) lo = 0x90;
      if (c == 0xf4) hi = 0x8f;
    } else {
      return i;
    }
    if (i + len > n) return i;
    if (b[i + 1] < lo || b[i + 1] > hi) return i;
    for (size_t k = 2; k < len; ++k)
      if (b[i + k] < 0x80 || b[i + k] > 0xbf) return i;
    i += len;
  }
  return std::string::npos;
}

// Walks the parser's events (no tree is built) and refuses what a scene never needs: more nodes than
// kMaxNodes once aliases are expanded, an alias inside the node it names (a cycle), nesting deeper than
// kMaxDepth, and tags other than YAML's standard ones (a scene holds plain values, lists and mappings).
class ShapeCheck : public YAML::EventHandler {
 public:
  ShapeCheck(std::string label, std::string kind) : label_(std::move(label)), kind_(std::move(kind)) {}
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t a) override { leaf(m, a, ""); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t a) override {
    const auto it = size_.find(a);
    if (it == size_.end())
      fail(m, "an alias refers to a node that contains it (a cycle); a " + kind_ + " cannot be recursive");
    add(m, it->second);
  }
  void OnScalar(const YAML::Mark& m, const std::string& tag, YAML::anchor_t a, const std::string&) override {
    leaf(m, a, tag);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string& tag, YAML::anchor_t a,
                       YAML::EmitterStyle::value) override {
    open(m, tag, a);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& m, const std::string& tag, YAML::anchor_t a, YAML::EmitterStyle::value) override {
    open(m, tag, a);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Open {
    YAML::anchor_t anchor;
    uint64_t nodes;
    YAML::Mark mark;
  };
  [[noreturn]] void fail(const YAML::Mark& m, const std::string& what) const {
    throw ConfigError(label_ + ": line " + std::to_string(m.line + 1) + ", column " + std::to_string(m.column + 1) +
                      ": " + what);
  }
  void check_tag(const YAML::Mark& m, const std::string& tag) const {
    static const std::set<std::string> standard = {"",
                                                   "?",
                                                   "!",
                                                   "tag:yaml.org,2002:str",
                                                   "tag:yaml.org,2002:int",
                                                   "tag:yaml.org,2002:float",
                                                   "tag:yaml.org,2002:bool",
                                                   "tag:yaml.org,2002:null",
                                                   "tag:yaml.org,2002:map",
                                                   "tag:yaml.org,2002:seq"};
    if (!standard.count(tag))
      fail(m, "YAML tag '" + shown(tag.rfind("tag:yaml.org,2002:", 0) == 0 ? "!!" + tag.substr(18) : tag) +
                  "' is not allowed (a " + kind_ +
                  " holds plain values, lists and mappings; "
                  "allowed tags: !!str, !!int, !!float, !!bool, !!null, !!map, !!seq)");
  }
  void add(const YAML::Mark& m, uint64_t n) {
    uint64_t& to = stack_.empty() ? total_ : stack_.back().nodes;
    to = std::min(to + n, kMaxNodes + 1);
    if (to > kMaxNodes)
      fail(m, "more than " + std::to_string(kMaxNodes) + " values once YAML aliases (*name) are expanded; a " + kind_ +
                  " is far smaller (an alias bomb?)");
  }
  void leaf(const YAML::Mark& m, YAML::anchor_t a, const std::string& tag) {
    check_tag(m, tag);
    if (a) size_[a] = 1;
    add(m, 1);
  }
  void open(const YAML::Mark& m, const std::string& tag, YAML::anchor_t a) {
    check_tag(m, tag);
    if (stack_.size() >= size_t(kMaxDepth))
      fail(m, "lists and mappings nested deeper than " + std::to_string(kMaxDepth) + " levels");
    stack_.push_back({a, 1, m});
  }
  void close() {
    const Open o = stack_.back();
    stack_.pop_back();
    if (o.anchor) size_[o.anchor] = o.nodes;
    add(o.mark, o.nodes);
  }
  std::string label_, kind_;
  std::vector<Open> stack_;
  std::map<YAML::anchor_t, uint64_t> size_;
  uint64_t total_ = 0;
};

}  // namespace

void check_yaml_text(const std::string& text, const std::string& label, const std::string& kind) {
  if (text.size() > kMaxSceneBytes)
    throw ConfigError(label + ": " + std::to_string(text.size()) + " bytes; a " + kind + " file is at most " +
                      std::to_string(kMaxSceneBytes) + " bytes");
  for (size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = text[i];
    if ((c < 0x20 && c != '\n' && c != '\r' && c != '\t') || c == 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "0x%02x", c);
      throw ConfigError(label + ": " + position(text, i) + ": control byte " + b + ": not a text file (a " + kind +
                        " is YAML text in UTF-8)");
    }
  }
  if (const size_t bad = invalid_utf8(text); bad != std::string::npos) {
    char b[8];
    std::snprintf(b, sizeof b, "0x%02x", static_cast<unsigned char>(text[bad]));
    throw ConfigError(label + ": " + position(text, bad) + ": byte " + b + " is not UTF-8 (a " + kind +
                      " is YAML text in UTF-8; re-save the file as UTF-8)");
  }
  std::istringstream in(text);
  YAML::Parser parser(in);
  ShapeCheck check(label, kind);
  int documents = 0;
  try {
    while (parser.HandleNextDocument(check))
      if (++documents > 1) throw ConfigError(label + ": more than one YAML document (---); a " + kind + " is one");
  } catch (const YAML::Exception& e) {
    throw ConfigError(label + ": not valid YAML: " + e.what());
  }
}

std::string one_line(const std::string& m) {
  std::string out;
  for (unsigned char c : m) {
    if (c == '\n')
      out += "\\n";
    else if (c == '\r' || c == '\t')
      out += ' ';
    else if (c < 0x20 || c == 0x7f)
      out += '?';
    else
      out += static_cast<char>(c);
  }
  if (out.size() > 1200) out = out.substr(0, 800) + " ... " + out.substr(out.size() - 300);
  return out;
}

}  // namespace granuflow
