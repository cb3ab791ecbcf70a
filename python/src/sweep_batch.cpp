// Batch evaluation of sweep points; see sweep_batch.hpp. Every reduction below mirrors a named function of
// granuflow.result / granuflow.outputs, including the order of its floating-point operations and Python's number
// formatting, so that a row is bit-identical to the per-point path's.
#include "sweep_batch.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "granuflow/errors.hpp"
#include "granuflow/interrupt.hpp"
#include "granuflow/quantity.hpp"
#include "result_reductions.hpp"

namespace granuflow::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Python's format(x, spec) for the float presentation types used in the messages ("g", ".3g", ".4g", ".12g").
std::string pyfmt(double x, const char* spec) {
  if (std::isnan(x)) return "nan";  // C prints "-nan" for a NaN with its sign bit set; Python never does
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, x);
  return buf;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::pair<std::string, std::string> rpartition(const std::string& s) {  // str.rpartition(".")[0], [2]
  const auto k = s.rfind('.');
  return k == std::string::npos ? std::make_pair(std::string(), s) : std::make_pair(s.substr(0, k), s.substr(k + 1));
}

// outputs.size_fraction: "bed.d90" -> 0.9; nullopt for other names (regex ^(?:.*\.)?(d\d+)$).
std::optional<double> size_fraction(const std::string& name) {
  const std::string local = rpartition(name).second;
  if (local.size() < 2 || local[0] != 'd') return std::nullopt;
  for (size_t i = 1; i < local.size(); ++i)
    if (local[i] < '0' || local[i] > '9') return std::nullopt;
  return std::stoi(local.substr(1)) / 100.0;
}

// What the results of one flowsheet share (granuflow.result.Layout with the roles of granuflow.outputs).
struct Layout {
  struct Role {
    OutputRole role;
    std::string quantity, unit;
    int cls;
  };
  std::vector<Role> roles;                                      // per output column
  std::vector<std::string> output_names;                        // per output column
  std::unordered_map<std::string, std::pair<bool, int>> index;  // name -> (is output, column); outputs win
  std::unordered_map<std::string, std::string> units;           // Flowsheet.units()
  std::map<std::string, std::string> summary;                   // summary key -> source
  std::string scene_name;

  explicit Layout(const Scene& s) : summary(s.summary), scene_name(s.name) {
    for (const auto& u : s.flowsheet->units()) {
      for (const auto& x : u.spec.states()) units[u.state_prefix + x.name] = x.unit;
      for (const auto& x : u.spec.outputs()) {
        units[u.name + "." + x.name] = x.unit;
        roles.push_back({x.role, x.quantity, u.name, x.cls});
      }
    }
    output_names = s.flowsheet->output_names();
    const auto states = s.flowsheet->state_names();
    for (size_t i = 0; i < states.size(); ++i) index[states[i]] = {false, static_cast<int>(i)};
    for (size_t j = 0; j < output_names.size(); ++j) index[output_names[j]] = {true, static_cast<int>(j)};
  }
  std::string unit_of(const std::string& name) const {
    const auto it = units.find(name);
    return it == units.end() ? std::string() : it->second;
  }
};

// One run as granuflow.result.Result reads it.
struct View {
  const Layout& L;
  const SimResult& r;
  double rtol;
  size_t nt() const { return r.t.size(); }
  size_t no() const { return L.output_names.size(); }
  double out(size_t k, size_t j) const { return r.outputs[k * no() + j]; }
  BlockView block() const {
    return BlockView::dense(r.outputs, static_cast<std::ptrdiff_t>(nt()), static_cast<std::ptrdiff_t>(no()));
  }
  double final_of(const std::string& name) const {
    const auto& [is_out, i] = L.index.at(name);
    const size_t k = nt() - 1;
    return is_out ? out(k, i) : r.y[k * r.state_names.size() + i];
  }
};

struct GridEnd {
  std::string name;
  double initial, final, max;
  std::optional<double> d_um;
};

double from_si_um(double v) {  // quantity.from_si(v, "um", "m")
  const double a = to_si(0.0, "um", "m", "unit");
  return (v - a) / (to_si(1.0, "um", "m", "unit") - a);
}

// Result.grid_ends
std::vector<GridEnd> grid_ends(const View& v) {
  std::vector<GridEnd> out;
  std::set<std::string> psd;
  for (const auto& ro : v.L.roles)
    if (ro.role == OutputRole::kSizeMass) psd.insert(ro.unit);
  const size_t nt = v.nt();
  for (const auto& unit : psd) {
    std::vector<std::pair<int, int>> d, m;  // (class, column)
    for (size_t j = 0; j < v.L.roles.size(); ++j) {
      const auto& ro = v.L.roles[j];
      if (ro.unit != unit) continue;
      if (ro.role == OutputRole::kSizeDiameter) d.emplace_back(ro.cls, static_cast<int>(j));
      if (ro.role == OutputRole::kSizeMass) m.emplace_back(ro.cls, static_cast<int>(j));
    }
    std::sort(d.begin(), d.end());
    std::sort(m.begin(), m.end());
    if (d.size() != m.size())  // Result.grid_ends would fail on it as well
      throw std::runtime_error("unit " + unit + ": size distribution with " + std::to_string(m.size()) +
                               " class masses but " + std::to_string(d.size()) + " pivot diameters");
    std::vector<std::ptrdiff_t> mass_cols;
    for (const auto& [cls, col] : m) mass_cols.push_back(col);
    const auto f = end_fractions(v.block(), mass_cols, {0, static_cast<std::ptrdiff_t>(m.size()) - 1});
    out.push_back({unit + ".bottom_class", f[0][0], f[0][1], f[0][2], from_si_um(v.out(0, d.front().second))});
    out.push_back({unit + ".top_class", f[1][0], f[1][1], f[1][2], from_si_um(v.out(0, d.back().second))});
  }
  for (size_t j = 0; j < v.L.roles.size(); ++j)
    if (v.L.roles[j].role == OutputRole::kGridEnd && !psd.count(v.L.roles[j].unit))
      out.push_back({v.L.output_names[j],
                     v.out(0, j),
                     v.out(nt - 1, j),
                     column_max(v.block(), static_cast<std::ptrdiff_t>(j)),
                     {}});
  return out;
}

// outputs.grid_end_warnings without a grid check (a sweep point runs none)
void grid_end_warnings(const std::vector<GridEnd>& ends, double lim, std::vector<std::string>& out) {
  const std::string when = "at the end of the run";
  for (const auto& e : ends) {
    const auto [unit, end] = rpartition(e.name);
    const std::string where = end == "top_class"      ? "top size class"
                              : end == "bottom_class" ? "bottom size class"
                                                      : e.name;
    const std::string at = e.d_um ? " (" + pyfmt(*e.d_um, "%.4g") + " um)" : "";
    const std::string side = end == "bottom_class" ? "d_min" : "d_max";
    if (e.initial > lim) {
      out.push_back(unit + ": the initial size distribution lies outside the grid: " + pyfmt(100 * e.initial, "%.3g") +
                    " % of the initial mass is in the " + where + at +
                    "; check the initial distribution against the grid (particles: settings: d_min, d_max)");
    } else if (e.max > lim) {
      const std::string peak = e.max > 1.01 * e.final ? " (up to " + pyfmt(100 * e.max, "%.3g") + " % during it)" : "";
      out.push_back(unit + ": " + pyfmt(100 * e.final, "%.3g") + " % of the mass is in the " + where + at + " " + when +
                    peak + ": the grid clips the distribution (more than " + pyfmt(100 * lim, "%g") +
                    " %), so the sizes near that end are the grid's, not the product's: either the grid is too coarse "
                    "(mass smeared into the end class: more classes) or too short (widen it: particles: settings: " +
                    side + "); the grid check of a plain run tells which");
    }
  }
}

struct Clipped {
  std::string key, note;
};

// Result.end_class_percentiles
std::vector<Clipped> end_class_percentiles(const View& v, const std::vector<GridEnd>& ends) {
  std::vector<Clipped> out;
  auto find = [&](const std::string& name) -> const GridEnd* {
    for (const auto& e : ends)
      if (e.name == name) return &e;
    return nullptr;
  };
  for (const auto& [key, src] : v.L.summary) {
    const auto frac = size_fraction(src);
    if (!frac) continue;
    const auto [unit, name] = rpartition(src);
    const GridEnd* top = find(unit + ".top_class");
    const GridEnd* bottom = find(unit + ".bottom_class");
    const GridEnd* e = nullptr;
    std::string end, which, word;
    if (top && top->final > 1.0 - *frac + 1e-12)
      e = top, end = "top", which = "lower", word = "at least";
    else if (bottom && bottom->final > *frac + 1e-12)
      e = bottom, end = "bottom", which = "upper", word = "at most";
    if (!e) continue;
    const double d_um = std::strtod(pyfmt(*e->d_um, "%.12g").c_str(), nullptr);  // the pivot without m -> um roundoff
    const double value = ends_with(key, "_um") ? d_um : d_um * 1e-6;
    out.push_back({key, unit + ": " + name + " lies in the " + end + " size class (" + pyfmt(100 * e->final, "%.3g") +
                            " % of the mass there): " + word + " the grid's end, " + pyfmt(d_um, "%.4g") +
                            " um; summary " + key + " is null, " + key + "_" + which +
                            "_bound = " + pyfmt(value, "%.4g")});
  }
  return out;
}

std::optional<double> finite(double x) { return std::isfinite(x) ? std::optional<double>(x) : std::nullopt; }

// Result.balance_closure, as outputs.balance_closures lists it: (name, closure) of the tracked quantities.
std::vector<std::pair<std::string, double>> balance_closures(const View& v, const ResultRules& rules) {
  struct Acc {
    double in = 0.0, out = 0.0, hold0 = 0.0, hold = 0.0;
  };
  std::map<std::string, Acc> acc;
  const size_t last = v.nt() - 1;
  for (size_t j = 0; j < v.L.roles.size(); ++j) {
    const auto& ro = v.L.roles[j];
    if (ro.role != OutputRole::kBalanceIn && ro.role != OutputRole::kBalanceOut && ro.role != OutputRole::kBalanceHold)
      continue;
    Acc& a = acc[ro.quantity];
    if (ro.role == OutputRole::kBalanceHold)
      a.hold0 += v.out(0, j), a.hold += v.out(last, j);
    else
      (ro.role == OutputRole::kBalanceIn ? a.in : a.out) += v.out(last, j) - v.out(0, j);
  }
  std::vector<std::string> names = rules.balance_quantities;
  for (const auto& [q, a] : acc)  // each named solid of a composed particle system, sorted
    if (q.rfind("solids:", 0) == 0) names.push_back(q);
  std::vector<std::pair<std::string, double>> out;
  for (const auto& q : names) {
    const auto it = acc.find(q);
    if (it == acc.end()) continue;
    const Acc& a = it->second;
    double scale = std::abs(a.hold0);  // Python's max(): the first of equals, NaN only where it comes first
    for (double x : {std::abs(a.hold), std::abs(a.in), std::abs(a.out), 1e-300})
      if (x > scale) scale = x;
    if (const auto c = finite(std::abs(a.hold - a.hold0 - (a.in - a.out)) / scale)) out.emplace_back(q, *c);
  }
  return out;
}

// outputs.balance_findings at the end of a run: (warnings, failures)
std::pair<std::vector<std::string>, std::vector<std::string>> balance_findings(const View& v,
                                                                               const ResultRules& rules) {
  const double warn_at =
      std::min(std::max(rules.balance_warn_min, rules.balance_warn_factor * v.rtol), rules.balance_warn_max);
  const double fail_at = rules.balance_fail;
  auto closures = balance_closures(v, rules);
  std::stable_sort(closures.begin(), closures.end(),
                   [](const auto& a, const auto& b) { return -a.second < -b.second; });
  std::vector<std::string> warns, fails;
  const std::string when = "at the end of the run";
  for (const auto& [name, c] : closures) {
    if (c <= warn_at) continue;
    const std::string what = name.substr(0, name.find('.')) == "energy" ? "energy" : "mass";
    if (c > fail_at) {
      fails.push_back("balance: the " + name + " balance does not close " + when + ": closure " + pyfmt(c, "%.3g") +
                      " (more than " + pyfmt(fail_at, "%g") + "): a unit loses or creates " + what +
                      "; no solver tolerance explains it");
      warns.push_back(fails.back());
    } else {
      warns.push_back("balance: the " + name + " balance closes only to " + pyfmt(c, "%.3g") + " " + when +
                      " (more than " + pyfmt(warn_at, "%g") + " for rtol " + pyfmt(v.rtol, "%g") +
                      "): tighten the solver's tolerances (solver: rtol, atol) or check the units");
    }
  }
  return {warns, fails};
}

// The sweep row of one run: runner.final_values and Result.warnings (ok), or Result.check_balance's failure.
void reduce(const View& v, const BatchRequest& req, PointOutcome& p) {
  if (v.nt() == 0) throw std::runtime_error("a run without output times");  // never made by simulate()
  auto [warns, fails] = balance_findings(v, req.rules);
  if (!fails.empty()) {
    p.message = v.L.scene_name + ": " + fails[0];
    return;
  }
  const auto ends = grid_ends(v);
  const auto clipped = end_class_percentiles(v, ends);
  std::vector<std::string> w;
  grid_end_warnings(ends, req.rules.grid_end_warning, w);
  for (const auto& c : clipped) w.push_back(c.note);
  w.insert(w.end(), warns.begin(), warns.end());
  for (size_t k = 0; k < w.size(); ++k) p.message += (k ? "; warning: " : "warning: ") + w[k];
  const auto& std_keys = req.rules.standard_summary_keys;
  p.values.assign(req.outputs.size(), kNaN);
  for (size_t k = 0; k < req.outputs.size(); ++k) {
    const std::string& o = req.outputs[k];
    const auto src = v.L.summary.find(o);
    if (src == v.L.summary.end() && std::find(std_keys.begin(), std_keys.end(), o) == std_keys.end()) {
      p.values[k] = v.final_of(o);
      continue;
    }
    const bool is_clipped = std::any_of(clipped.begin(), clipped.end(), [&](const Clipped& c) { return c.key == o; });
    if (src == v.L.summary.end() || is_clipped) continue;
    const std::string si = v.L.unit_of(src->second);
    const std::string unit = ends_with(o, "_um") ? "um" : si;  // outputs.summary_unit
    double x = v.final_of(src->second);
    if (!unit.empty() && unit != si) {  // quantity.from_si
      const double a = to_si(0.0, unit, si, "unit");
      x = (x - a) / (to_si(1.0, unit, si, "unit") - a);
    }
    p.values[k] = finite(x).value_or(kNaN);
  }
  p.ok = true;
}

void evaluate_point(Scene& s, const Layout& L, const SimOptions& o, const BatchRequest& req, size_t i,
                    PointOutcome& p) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t np = req.params.size();
  try {
    for (size_t k = 0; k < np; ++k) s.flowsheet->set_param(req.params[k], req.base[k]);
    for (size_t k = 0; k < np; ++k)
      if (req.given[i * np + k]) s.flowsheet->set_param(req.params[k], req.values[i * np + k]);
    p.params.resize(np);
    for (size_t k = 0; k < np; ++k) p.params[k] = s.flowsheet->param(req.params[k]);
    p.params_set = true;
    SimResult r;
    try {
      r = simulate(*s.flowsheet, o);
    } catch (const ConfigError& e) {
      throw ConfigError(runtime_config_message(s, e.what()));
    }
    p.solve_time_s = r.wall_time_s;
    reduce(View{L, r, o.rtol}, req, p);
  } catch (const SolverError& e) {
    p.message = e.what();
  } catch (const ConfigError& e) {
    p.message = e.what();
  }
  p.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string runtime_config_message(const Scene& s, const std::string& what) {
  if (s.path.empty() || what.rfind(s.path, 0) == 0) return what;
  return s.path + ": " + what;
}

SimOptions run_options(const Scene& s, const RunOverrides& ov) {
  SimOptions o = s.options;
  // An empty list would silently mean "the scene's output times"; the scene file refuses `times: []` too.
  if (ov.t_out && ov.t_out->empty())
    throw ConfigError("simulate(): t_out = []: expected a non-empty list of times in [0, t_end] (or n_out)");
  if (ov.t_end) {
    o.t_end = *ov.t_end;
    if (!ov.t_out) o.t_out.clear();
  }
  if (ov.t_out) o.t_out = *ov.t_out;
  if (ov.n_out) o.n_out = *ov.n_out, o.t_out.clear();
  if (ov.rtol) o.rtol = *ov.rtol;
  if (ov.atol) o.atol = *ov.atol;
  if (ov.linear_solver) o.linear_solver = parse_linear_solver(*ov.linear_solver, "simulate(): linear_solver");
  if (ov.max_steps) o.max_steps = *ov.max_steps;
  if (ov.method) o.method = parse_method(*ov.method, "simulate(): method");
  return o;
}

std::vector<PointOutcome> run_batch(const std::vector<Scene*>& scenes, const BatchRequest& req,
                                    const std::function<void(size_t)>& done) {
  const size_t n = req.n_points();
  std::vector<PointOutcome> out(n);
  if (n == 0 || scenes.empty()) return out;
  std::vector<SimOptions> opts;
  std::string bad_options;  // options the core refuses: every point fails with the message, as each run would
  try {
    for (Scene* s : scenes) opts.push_back(run_options(*s, req.overrides));
    validate_as(opts[0], "SimOptions.", "simulate(): ");
  } catch (const ConfigError& e) {
    bad_options = e.what();
  }
  const Layout layout(*scenes[0]);  // names and roles: the same on every clone
  std::atomic<size_t> next{0}, finished{0};
  std::mutex mu;
  std::condition_variable cv;
  std::exception_ptr error;
  auto work = [&](size_t w) {
    try {
      for (size_t i; (i = next++) < n;) {
        if (!bad_options.empty())
          out[i].message = bad_options;
        else
          evaluate_point(*scenes[w], layout, opts[w], req, i, out[i]);
        ++finished;
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu);
      if (!error) error = std::current_exception();
      next = n;  // the others stop at their next point
    }
    std::lock_guard<std::mutex> lock(mu);
    cv.notify_all();
  };
  std::vector<std::thread> threads;
  const size_t nw = std::min(scenes.size(), n);
  for (size_t w = 1; w < nw; ++w) threads.emplace_back(work, w);
  if (done) {  // the calling thread reports progress while the workers solve
    threads.emplace_back(work, 0);
    std::unique_lock<std::mutex> lock(mu);
    while (finished < n && !error) {
      cv.wait_for(lock, std::chrono::milliseconds(200));
      lock.unlock();
      try {
        done(finished);
      } catch (...) {  // an interrupt in the callback: stop the workers' runs at once, then rethrow it
        request_interrupt();
        lock.lock();
        if (!error) error = std::current_exception();
        next = n;
        break;
      }
      lock.lock();
    }
  } else {
    work(0);
  }
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
  return out;
}

}  // namespace granuflow::python
