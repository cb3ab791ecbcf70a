// SI units used inside granuflow and the conversions allowed at the edges (scene files, plots).
// A parameter declares its SI unit from the checked set below; a scene value may carry any unit of the
// same dimension ("60 degC", "700 m3/h", "90 g/min", "200 um") and is converted once, on loading.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

// True if `si_unit` is one of the SI units granuflow parameters and states may declare.
bool is_known_si_unit(const std::string& si_unit);

// The checked set, for error messages and docs.
const std::vector<std::string>& known_si_units();

// Converts `value` given in `from_unit` to the SI unit `si_unit`; throws ConfigError naming `where` when the
// unit is unknown or of another dimension. An empty `from_unit` means the value is already SI.
double to_si(double value, const std::string& from_unit, const std::string& si_unit, const std::string& where);

// Parses "60 degC" / "1e-3" / "700 m3/h" into value and unit text (unit empty when absent).
bool parse_quantity(const std::string& text, double* value, std::string* unit);

}  // namespace granuflow
