#include "granuflow/quantity.hpp"

#include <pthread.h>
#include <udunits2.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <regex>
#include <stdexcept>
#include <utility>

#include "granuflow/errors.hpp"

namespace granuflow {
namespace {

// Units are parsed by UDUNITS-2 (Unidata; Debian's libudunits2): SI prefixes, products ("Pa s", "kg.m-3"),
// quotients ("kg/(m2 s)") and powers ("m^3", "m3") compose, so any unit of the right dimension is accepted without a
// list growing one unit at a time. Three spellings of the field mean something else to its grammar, or nothing.
const std::pair<const char*, const char*> kSpellings[] = {
    {"-", "1"},              // dimensionless, as the papers' tables write it
    {"wt%", "%"},            // a mass fraction in per cent
    {"J/kg K", "J/(kg K)"},  // the engineering reading (UDUNITS would read J K / kg)
};

// Common units offered as examples when a unit is not understood (examples only: any composition is accepted).
const char* const kExamples[] = {
    "-",     "%",     "K",        "degC",      "m",        "mm",      "um",    "m2",   "m3",   "L",    "kg",
    "g",     "s",     "min",      "h",         "1/s",      "kg/s",    "g/min", "kg/h", "m3/s", "m3/h", "m/s",
    "kg/kg", "g/kg",  "kg/m3",    "g/L",       "Pa",       "kPa",     "bar",   "W",    "kW",   "J",    "kJ",
    "J/kg",  "kJ/kg", "J/(kg K)", "kJ/(kg K)", "W/(m2 K)", "W/(m K)", "W/K",   "m2/s", "Pa s", "mPa s"};

struct UtFree {
  void operator()(ut_unit* u) const { ut_free(u); }
};
using UnitPtr = std::unique_ptr<ut_unit, UtFree>;

// One parsed unit: its affine map to the base-SI product (si = factor * value + offset) and that product's text.
struct Parsed {
  bool ok = false;
  double factor = 1, offset = 0;
  std::string base;  // "m-3.kg", "K", "1"
};

// UDUNITS-2 keeps parser state in globals and is not thread-safe: reading the database and every parse go through
// one process-wide lock, and each unit text is parsed once per process (scenes are loaded from many threads at once
// in sweeps). The lock is a namespace-scope mutex, not a function-local static, so that fork() can hold it (below).
std::mutex g_units_mutex;

class UnitSystem {
 public:
  // The system, read on first use (the caller holds g_units_mutex); a missing database throws, and the next call
  // tries again.
  static UnitSystem& locked() {
    static UnitSystem* s = nullptr;
    if (!s) s = new UnitSystem();  // never freed: parses may run until the process exits
    return *s;
  }
  static void load() {
    std::lock_guard<std::mutex> lock(g_units_mutex);
    locked();
  }
  // The affine map of a unit text onto its base-SI product ({ok = false} when the text is not a plain unit).
  static Parsed parse(const std::string& text) {
    std::lock_guard<std::mutex> lock(g_units_mutex);
    UnitSystem& u = locked();
    auto it = u.cache_.find(text);
    if (it != u.cache_.end()) return it->second;
    Parsed p = u.parse_locked(text);
    u.cache_.emplace(text, p);
    return p;
  }

 private:
  UnitSystem() {
    ut_set_error_message_handler(ut_ignore);
    sys_ = ut_read_xml(nullptr);  // the database Debian installs (or $UDUNITS2_XML_PATH)
    if (!sys_) throw std::runtime_error("granuflow: the UDUNITS-2 unit database could not be read (libudunits2-data)");
  }
  static std::string spelled(const std::string& text) {
    for (const auto& [field, ud] : kSpellings)
      if (text == field) return ud;
    return text;
  }
  // Only plain unit expressions: no time origins ("s since 2000-01-01"), logarithmic units ("lg(re 1 mW)"),
  // control characters or surrounding blanks, which the grammar would quietly accept.
  static bool plain(const std::string& t) {
    if (t.empty() || t.front() == ' ' || t.back() == ' ') return false;
    for (unsigned char c : t)
      if (c < 0x20 || c == '@' || c == ':') return false;
    return t.find("since") == std::string::npos && t.find("re ") == std::string::npos &&
           t.find("after") == std::string::npos && t.find("from") == std::string::npos;
  }
  Parsed parse_locked(const std::string& text) {
    Parsed p;
    const std::string t = spelled(text);
    if (!plain(t)) return p;
    UnitPtr u(ut_parse(sys_, t.c_str(), UT_UTF8));
    if (!u) return p;
    char buf[256];
    const int n = ut_format(u.get(), buf, sizeof buf, UT_ASCII | UT_DEFINITION);
    if (n < 0 || n >= static_cast<int>(sizeof buf)) return p;
    // The definition is "[scale ]product[ @ origin]"; the product alone names the dimension in base SI units.
    std::string def(buf, n);
    if (const auto at = def.find(" @ "); at != std::string::npos) def = def.substr(0, at);
    if (const auto sp = def.find(' '); sp != std::string::npos && std::isdigit(static_cast<unsigned char>(def[0])))
      def = def.substr(sp + 1);
    const bool scaled = std::isdigit(static_cast<unsigned char>(def[0])) != 0 && def != "1";
    if (scaled || def.find('(') != std::string::npos) return p;
    UnitPtr base(ut_parse(sys_, def.c_str(), UT_ASCII));
    if (!base) return p;
    cv_converter* cv = ut_get_converter(u.get(), base.get());
    if (!cv) return p;
    p.offset = cv_convert_double(cv, 0.0);
    p.factor = cv_convert_double(cv, 1.0) - p.offset;
    cv_free(cv);
    p.ok = std::isfinite(p.factor) && std::isfinite(p.offset) && p.factor != 0;
    p.base = def;
    return p;
  }
  ut_system* sys_ = nullptr;
  std::map<std::string, Parsed> cache_;
};

// The dimension of a parsed unit in the project's SI spelling where it has one ("W/K"), else the base product.
std::string si_spelling(const Parsed& p) {
  for (const char* e : kExamples) {
    const Parsed q = UnitSystem::parse(e);
    if (q.ok && q.base == p.base && q.factor == 1 && q.offset == 0) return e;
  }
  return p.base;
}

std::string examples_for(const Parsed& si) {
  std::string out;
  for (const char* e : kExamples) {
    const Parsed p = UnitSystem::parse(e);
    if (p.ok && p.base == si.base) out += (out.empty() ? "" : ", ") + std::string(e);
  }
  return out;
}

}  // namespace

void load_unit_database() { UnitSystem::load(); }

namespace {
// fork() copies only the thread that calls it. A child forked while another thread reads the database (the Python
// module does that on a thread of its own at import) or parses a unit would find the lock held by a thread it does
// not have, and wait on it forever at its first unit. So fork waits until no thread is inside, and both processes
// release the lock after it.
[[maybe_unused]] const int kForkHandlers =
    pthread_atfork([] { g_units_mutex.lock(); }, [] { g_units_mutex.unlock(); }, [] { g_units_mutex.unlock(); });
}  // namespace

bool is_known_si_unit(const std::string& si_unit) {
  // A coherent SI unit: understood, and equal to its base-SI product without a scale or an origin.
  const Parsed p = UnitSystem::parse(si_unit);
  return p.ok && p.factor == 1 && p.offset == 0;
}

const std::vector<std::string>& known_si_units() {
  static const std::vector<std::string> units = [] {
    std::vector<std::string> v;
    for (const char* e : kExamples)
      if (is_known_si_unit(e)) v.push_back(e);
    return v;
  }();
  return units;
}

std::string setting_si_unit(const std::string& description) {
  static const std::regex word(R"(,\s*([^\s,()]+))");
  const auto& known = known_si_units();
  for (auto it = std::sregex_iterator(description.begin(), description.end(), word); it != std::sregex_iterator();
       ++it) {
    const std::string w = (*it)[1].str();
    if (w != "-" && std::find(known.begin(), known.end(), w) != known.end()) return w;
  }
  return "";
}

double to_si(double value, const std::string& from_unit, const std::string& si_unit, const std::string& where) {
  if (from_unit.empty() || from_unit == si_unit) return value;
  const Parsed si = UnitSystem::parse(si_unit);
  if (!si.ok) throw std::logic_error(where + ": declared SI unit '" + si_unit + "' is not understood");
  const Parsed from = UnitSystem::parse(from_unit);
  if (!from.ok) {
    const std::string ex = examples_for(si);
    throw ConfigError(where + ": unknown unit '" + from_unit + "' (allowed: any unit of " + si_unit +
                      (ex.empty() ? "" : ", e.g. " + ex) + ")");
  }
  if (from.base != si.base)
    throw ConfigError(where + ": unit '" + from_unit + "' is " + si_spelling(from) + ", but the value must be in " +
                      si_unit);
  // Through the base product: value -> base -> si (si itself is coherent, factor 1 and offset 0, for declared units).
  const double base_value = from.factor * value + from.offset;
  if (si.factor == 1 && si.offset == 0) return base_value;
  return (base_value - si.offset) / si.factor;
}

bool parse_quantity(const std::string& text, double* value, std::string* unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin) return false;
  std::string rest(end);
  const auto first = rest.find_first_not_of(" \t");
  rest = first == std::string::npos ? "" : rest.substr(first, rest.find_last_not_of(" \t") - first + 1);
  *value = v;
  *unit = rest;
  return true;
}

}  // namespace granuflow
