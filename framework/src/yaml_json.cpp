// See yaml_json.hpp. The patterns are PyYAML's implicit resolvers (yaml/resolver.py) and its constructors'
// conversions (yaml/constructor.py, SafeConstructor), written out for yaml-cpp's nodes.
#include "yaml_json.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <regex>
#include <vector>

#include "granuflow/errors.hpp"

namespace granuflow {
namespace {

const std::regex& re(int which) {
  static const std::regex kBool("^(?:yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF)$");
  static const std::regex kFloat(
      "^(?:[-+]?(?:[0-9][0-9_]*)\\.[0-9_]*(?:[eE][-+][0-9]+)?|\\.[0-9][0-9_]*(?:[eE][-+][0-9]+)?"
      "|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\\.[0-9_]*|[-+]?\\.(?:inf|Inf|INF)|\\.(?:nan|NaN|NAN))$");
  static const std::regex kInt(
      "^(?:[-+]?0b[0-1_]+|[-+]?0[0-7_]+|[-+]?(?:0|[1-9][0-9_]*)|[-+]?0x[0-9a-fA-F_]+"
      "|[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+)$");
  static const std::regex kNull("^(?:~|null|Null|NULL|)$");
  static const std::regex* all[] = {&kBool, &kFloat, &kInt, &kNull};
  return *all[which];
}
enum { kBoolRe, kFloatRe, kIntRe, kNullRe };

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);  // UTF-8 passes through: JSON text is UTF-8
        }
    }
  }
  return out + "\"";
}

std::string number(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "Infinity" : "-Infinity";
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);  // shortest round trip: Python reads the same double
  std::string s(buf, r.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // stays a float in Python
  return s;
}

// Decimal digits pass through as they are; the other forms are converted here, in 64 bits.
constexpr const char* kIntLimit = " (binary, octal, hexadecimal and base-60 integers must be below 2^64)";

// SafeConstructor.construct_yaml_int: sign, underscores, 0b / 0x / leading-0 octal, base 60. Python's int has no
// limit; JSON carries the digits, so a huge one stays exact.
std::string int_json(std::string v) {
  v.erase(std::remove(v.begin(), v.end(), '_'), v.end());
  std::string sign;
  if (v[0] == '-' || v[0] == '+') sign = v[0] == '-' ? "-" : "", v = v.substr(1);
  if (v == "0") return "0";
  auto from_base = [&](const std::string& digits, int base) -> std::string {
    unsigned long long x = 0;
    const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), x, base);
    if (r.ec != std::errc()) throw ConfigError("integer " + sign + v + " is too large" + kIntLimit);
    return sign + std::to_string(x);
  };
  if (v.rfind("0b", 0) == 0) return from_base(v.substr(2), 2);
  if (v.rfind("0x", 0) == 0) return from_base(v.substr(2), 16);
  if (v[0] == '0') return from_base(v.substr(1), 8);
  if (v.find(':') != std::string::npos) {
    unsigned long long x = 0;
    size_t start = 0;
    while (true) {
      const size_t colon = v.find(':', start);
      unsigned long long part = 0;
      const std::string digits = v.substr(start, colon - start);
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), part);
      if (r.ec != std::errc() || x > (std::numeric_limits<unsigned long long>::max() - part) / 60)
        throw ConfigError("integer " + sign + v + " is too large" + kIntLimit);
      x = x * 60 + part;
      if (colon == std::string::npos) break;
      start = colon + 1;
    }
    return sign + std::to_string(x);
  }
  const size_t nz = v.find_first_not_of('0');
  return sign + (nz == std::string::npos ? "0" : v.substr(nz));
}

// SafeConstructor.construct_yaml_float
std::string float_json(std::string v) {
  v.erase(std::remove(v.begin(), v.end(), '_'), v.end());
  for (auto& c : v) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  double sign = 1.0;
  if (v[0] == '-' || v[0] == '+') sign = v[0] == '-' ? -1.0 : 1.0, v = v.substr(1);
  if (v == ".inf") return number(sign * std::numeric_limits<double>::infinity());
  if (v == ".nan") return number(std::numeric_limits<double>::quiet_NaN());
  if (v.find(':') != std::string::npos) {  // from the last part up, as PyYAML sums them
    std::vector<double> parts;
    for (size_t start = 0;;) {
      const size_t colon = v.find(':', start);
      parts.push_back(std::stod(v.substr(start, colon - start)));
      if (colon == std::string::npos) break;
      start = colon + 1;
    }
    double x = 0.0, base = 1.0;
    for (auto it = parts.rbegin(); it != parts.rend(); ++it) x += *it * base, base *= 60;
    return number(sign * x);
  }
  double x = 0.0;
  const auto r = std::from_chars(v.data(), v.data() + v.size(), x);  // "1." and ".5" are read whole
  // Beyond double's range Python's float() gives inf, or 0 below it: so does PyYAML, so does this.
  if (r.ec == std::errc::result_out_of_range)
    x = v.find("e-") == std::string::npos ? std::numeric_limits<double>::infinity() : 0.0;
  else if (r.ec != std::errc() || r.ptr != v.data() + v.size())
    x = std::stod(v);
  return number(sign * x);
}

std::string scalar_json(const YAML::Node& n) {
  const std::string& v = n.Scalar();
  const std::string& tag = n.Tag();
  const std::string std_tag = "tag:yaml.org,2002:";
  std::string kind;
  if (tag == "?") {  // plain: resolved by its text
    if (!v.empty()) {
      const char c = v[0];
      if (std::string("yYnNtTfFoO").find(c) != std::string::npos && std::regex_match(v, re(kBoolRe)))
        kind = "bool";
      else if (std::string("-+0123456789.").find(c) != std::string::npos && std::regex_match(v, re(kFloatRe)))
        kind = "float";
      else if (std::string("-+0123456789").find(c) != std::string::npos && std::regex_match(v, re(kIntRe)))
        kind = "int";
    }
    if (kind.empty() && std::regex_match(v, re(kNullRe))) kind = "null";
  } else if (tag.rfind(std_tag, 0) == 0) {
    kind = tag.substr(std_tag.size());
  }
  if (kind == "bool") {
    const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(v[0])));
    return c == 'y' || c == 't' || (c == 'o' && v.size() == 2) ? "true" : "false";
  }
  if (kind == "int") return int_json(v);
  if (kind == "float") return float_json(v);
  if (kind == "null") return "null";
  return quoted(v);  // "!" (quoted), !!str, a timestamp's text
}

void write(const YAML::Node& n, std::string& out) {
  switch (n.Type()) {
    case YAML::NodeType::Null:
      out += "null";
      return;
    case YAML::NodeType::Scalar:
      try {
        out += scalar_json(n);
      } catch (const ConfigError& e) {  // where in the file: the caller names the file and the section
        throw ConfigError("line " + std::to_string(n.Mark().line + 1) + ": " + e.what());
      }
      return;
    case YAML::NodeType::Sequence: {
      out += '[';
      bool first = true;
      for (const auto& item : n) {
        if (!first) out += ", ";
        first = false;
        write(item, out);
      }
      out += ']';
      return;
    }
    case YAML::NodeType::Map: {
      out += '{';
      bool first = true;
      for (const auto& kv : n) {
        if (!first) out += ", ";
        first = false;
        out += quoted(kv.first.IsScalar() ? kv.first.Scalar() : YAML::Dump(kv.first));
        out += ": ";
        write(kv.second, out);
      }
      out += '}';
      return;
    }
    case YAML::NodeType::Undefined:
      out += "null";
      return;
  }
}

}  // namespace

std::string yaml_json(const YAML::Node& node) {
  std::string out;
  write(node, out);
  return out;
}

}  // namespace granuflow
