// SI units used inside granuflow and the conversions allowed at the edges (scene files, plots).
// A parameter declares a coherent SI unit; a scene value may carry any unit of the same dimension ("60 degC",
// "700 m3/h", "90 g/min", "200 um", "5 kW/K"), parsed by UDUNITS-2, and is converted once, on loading.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

// True if `si_unit` is a coherent SI unit (understood, no scale, no origin): what parameters and states declare.
bool is_known_si_unit(const std::string& si_unit);

// The common coherent SI units, for docs and for finding a unit in a setting's description.
const std::vector<std::string>& known_si_units();

// The SI unit a real setting declares in its description, after a comma ("smallest pivot diameter, m (Table 5)"); ""
// for a plain number. Settings::get_real converts a value with a unit to it; the Python package reads it from here.
std::string setting_si_unit(const std::string& description);

// Converts `value` given in `from_unit` to the SI unit `si_unit`; throws ConfigError naming `where` when the
// unit is unknown or of another dimension. An empty `from_unit` means the value is already SI.
double to_si(double value, const std::string& from_unit, const std::string& si_unit, const std::string& where);

// Parses "60 degC" / "1e-3" / "700 m3/h" into value and unit text (unit empty when absent).
bool parse_quantity(const std::string& text, double* value, std::string* unit);

// Reads the UDUNITS-2 unit database now (about 5 ms) instead of at the first unit parsed: the Python extension
// calls it on a thread of its own at import, so that the read overlaps the interpreter's imports. Safe to call from
// any thread, any number of times; the first call reads, the others wait for it.
void load_unit_database();

}  // namespace granuflow
