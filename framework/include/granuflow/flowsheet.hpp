// The flowsheet graph: named unit instances, connections between their ports, parameters addressed as
// "unit.param" and time-dependent inputs. finalize() lays out the global state vector (each unit a contiguous
// block) and resolves every port field to the global index of the state that provides it.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "granuflow/input.hpp"
#include "granuflow/param.hpp"
#include "granuflow/unit.hpp"

namespace granuflow {

// Settings given to one unit in a scene. A unit reads each one while declaring, with its type, default and
// allowed range; reading declares it. Settings the unit never reads are reported as unknown keys.
class Flowsheet;
struct UnitInstance;

class Settings {
 public:
  Settings() = default;
  // `where` prefixes messages, e.g. "scene.yaml: units.bed.settings".
  Settings(std::string where, std::map<std::string, std::string> given);

  long get_int(const std::string& name, long def, long lower, long upper, const std::string& description);
  double get_real(const std::string& name, double def, double lower, double upper, const std::string& description);
  bool get_bool(const std::string& name, bool def, const std::string& description);
  std::string get_choice(const std::string& name, const std::string& def, const std::vector<std::string>& choices,
                         const std::string& description);
  // Throws ConfigError naming the first setting that was given but never read, with the valid names.
  void check_all_used() const;
  // Settings named `now`... were named `before`... in earlier versions: a read of `now`X that is not given takes a
  // given `before`X, warning once per process that it is deprecated (a kernel's settings carry one name in every
  // unit). Both spellings given is an error.
  void rename_prefix(std::string now, std::string before) { renamed_.emplace_back(std::move(now), std::move(before)); }
  const std::vector<SettingSpec>& declared() const { return declared_; }
  const std::string& where() const { return where_; }
  // A unit instance added to the flowsheet before this one (a particle system other units share), or nullptr.
  const UnitInstance* unit(const std::string& name) const;
  void attach(const Flowsheet* fs) { fs_ = fs; }

 private:
  const std::string* given(const std::string& name);
  std::string where_;
  std::map<std::string, std::string> given_;
  std::vector<std::string> used_;
  std::vector<SettingSpec> declared_;
  std::vector<std::pair<std::string, std::string>> renamed_;  // (now, before) prefixes
  const Flowsheet* fs_ = nullptr;
};

struct UnitInstance {
  std::string name;
  std::unique_ptr<Unit> unit;
  UnitSpec spec;
  std::vector<SettingSpec> settings;
  int offset = 0;                                      // global index of own state 0
  std::vector<double> params;                          // current constant values (SI)
  std::vector<std::optional<PiecewiseLinear>> inputs;  // per param: time-dependent override
  std::vector<std::vector<int>> port_index;            // per port, per field: global state index
  std::vector<std::vector<int>> port_runs;             // per port, per field: consecutive states from it on
  std::vector<std::pair<int, int>> peers;              // per port: (unit index, port index) of the connected port
  int quad_offset = 0;                                 // global index of own quadrature 0
  int shared = -1;  // unit index of the particle system whose parameters it reads (UnitSpec::use_shared_params)
  int owner = -1;   // a companion (UnitSpec::add_companion): the unit that brought it
  // Qualifies the unit's state names: "name.", or for a companion "owner.<companion>_" (a granulator's discharge
  // flows are "gran.discharge_mdot_i" whichever unit computes them).
  std::string state_prefix;
};

class DaeSystem;

class Flowsheet {
 public:
  explicit Flowsheet(std::string name = "flowsheet") : name_(std::move(name)) {}
  Flowsheet(const Flowsheet&) = delete;
  Flowsheet& operator=(const Flowsheet&) = delete;

  const std::string& name() const { return name_; }

  // Building. add_unit calls unit->declare() and adds the unit's companions after it; connect takes "unit.port" on
  // both sides, out -> in (a companion's outlet under its owner's name for it).
  void add_unit(const std::string& name, std::unique_ptr<Unit> unit, Settings settings);
  void connect(const std::string& from, const std::string& to);
  // Resolves ports (every port connected once, matching kinds and class counts, every field provided by
  // exactly one side) and lays out the state vector. Throws ConfigError naming the port.
  void finalize();
  bool finalized() const { return finalized_; }

  // Parameters, by "unit.param". set_param validates against the declared bounds.
  std::vector<std::string> param_names() const;
  int param_id(const std::string& qualified) const;  // global id; throws ConfigError listing valid names
  double param(const std::string& qualified) const;
  void set_param(const std::string& qualified, double value_si);
  const ParamSpec& param_spec(int id) const;
  double param_value(int id) const;
  void set_param_value(int id, double value_si);
  // Makes `value_si` the parameter's default and current value, `source` where it comes from (a material); checked
  // against the declared bounds like set_param.
  void set_param_default(int id, double value_si, const std::string& source);
  std::pair<int, int> param_location(int id) const;  // (unit index, local param index)
  // A parameter driven by a time-dependent input takes its values from the input in every run, so
  // set_param / set_param_value on it are a ConfigError naming the input (a value set there would be ignored);
  // clear_input() first makes it a constant again (its last constant value), explicitly.
  void set_input(const std::string& qualified, PiecewiseLinear input);
  void clear_input(const std::string& qualified);
  bool has_input(int id) const;
  // The range a parameter may take: its declared bounds, narrowed by the declared bounds of every parameter
  // that follows it by a link (inlet.T may go no higher than the bed.T0 it sets). set_param, set_input and
  // calibration use these.
  std::pair<double, double> bounds(int id) const;
  // Links: parameter `target` takes the value of `source` (its value at t = 0 if `source` is an input) in every
  // run, e.g. the initial bed temperature follows the inlet temperature; a sensitivity with respect to `source`
  // includes the path through `target`. link() refuses a pair whose bounds do not overlap or a source whose
  // value the target cannot take, and narrows the source's bounds() to the overlap.
  // Setting a link target (set_param, set_input) to anything but the value it follows is a ConfigError that
  // names the link; param() of a link target is its source's value.
  void link(const std::string& target, const std::string& source);
  int link_source(int target) const;         // -1 unless `target` follows a parameter
  std::string qualified_name(int id) const;  // "unit.param"
  // The parameter values unit `u` runs with at t = 0: its own, link targets at their sources' values (checked
  // against the targets' bounds: a ConfigError names the link). Reading only: runs never change the flowsheet.
  std::vector<double> run_params(int u) const;
  // Every unit's check() on run_params(); a ConfigError from a unit names the unit instance. A unit with
  // time-dependent inputs is checked with the values a run sees at every knot of its inputs instead (a ramp of
  // the inlet temperature must not pass through states the model cannot represent), the message saying when.
  void check_units() const;
  // "unit NAME (TYPE): message" for a ConfigError a unit threw relative to itself.
  std::string qualify_unit_message(int u, const std::string& message) const;
  // "unit.port" as a scene names it: a companion's outlet by its owner's name for it.
  std::string port_label(int u, int p) const;
  std::vector<int> linked_targets(int source) const;
  // Breakpoints of all inputs inside (0, t_end).
  std::vector<double> breakpoints(double t_end) const;

  // Layout (after finalize).
  int n_states() const { return n_states_; }
  int n_explicit_states() const { return n_explicit_; }  // the last ones, belonging to explicit units
  int n_quadratures() const { return n_quads_; }
  std::vector<std::string> state_names() const;  // "unit.state"
  const StateSpec& state_spec(int global) const;
  int state_unit(int global) const;  // unit index owning a state
  int state_id(const std::string& qualified) const;
  std::vector<std::string> output_names() const;  // "unit.output"
  int n_outputs() const;

  std::vector<UnitInstance>& units() { return units_; }
  const std::vector<UnitInstance>& units() const { return units_; }
  int unit_index(const std::string& name) const;  // throws ConfigError listing valid names

  // A run's system (dae_system.hpp) with explicit units inlined or not: one a finished run gave back, begun anew
  // with the current parameters and inputs, else a new one. Building one configures every unit and allocates its
  // work arrays (0.56 ms of the 100-class sieve-mill loop's 42 ms, 0.08 ms of the headline's 7 ms, and the first
  // evaluations touch the memory again); runs in parallel threads each hold their own. The system goes back to the
  // flowsheet when the last copy of the handle is gone, if its run ended normally (DaeSystem::end_run). After
  // finalize().
  std::shared_ptr<DaeSystem> take_system(bool inline_explicit) const;

 private:
  std::pair<int, int> split_port(const std::string& qualified) const;
  void add_instance(const std::string& name, std::unique_ptr<Unit> unit, Settings settings);
  double linked_value(int source) const;
  int resolve_field(int u, int p, int f, int depth) const;
  void store_param(int id, double value_si);  // bounds-checked, ignores links
  std::string name_;
  std::vector<UnitInstance> units_;
  std::vector<std::pair<std::pair<int, int>, std::pair<int, int>>> connections_;
  std::map<std::pair<int, std::string>, std::pair<int, int>> aliases_;  // (owner, port name) -> companion's outlet
  std::vector<std::pair<int, int>> param_table_;                        // global param id -> (unit, local)
  std::vector<int> state_owner_;
  std::vector<std::pair<int, int>> links_;  // (target, source) parameter ids
  int n_states_ = 0;
  int n_explicit_ = 0;
  int n_quads_ = 0;
  bool finalized_ = false;
  struct SystemPool;  // flowsheet.cpp
  std::shared_ptr<SystemPool> pool_;
};

}  // namespace granuflow
