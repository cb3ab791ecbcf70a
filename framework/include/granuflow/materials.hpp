// The catalogue of solid materials: named sets of published property values with their citations.
//
// A scene names a material in its particle system (`particles: material: NAME`). Every parameter of the flowsheet
// whose name is one of the material's properties then starts from the material's value instead of the unit's
// built-in default (paper 001's maltodextrin), and its source names the material; the scene's own `params:` still
// override it. The solid's bulk properties (rho_s, eps_intra, rho_p, cp_s) apply to the particle system only;
// properties of the solid that kernels read (glass transition, sorption, drying) apply to every unit that declares
// a parameter of that name, bare or with the aggregation kernel's prefix `agg_`.
//
// A parameter that some material in the catalogue describes but the named material does not keeps the unit's
// built-in value (paper 001's maltodextrin) only openly: its source says so, and a run lists it (Scene::
// material_unsupplied) unless the scene sets it. Values enter the catalogue only with a published source; a value
// a source does not give is one the user supplies.
#pragma once
#include <string>
#include <vector>

namespace granuflow {

struct MaterialProperty {
  std::string name;         // the parameter it sets (local name, as `granuflow describe` lists it)
  double value;             // SI, in `unit`
  std::string unit;         // SI unit from quantity.hpp's checked set
  std::string source;       // where the value is published
  std::string description;  // what the value is, in a few words
};

struct Material {
  std::string name;         // catalogue key, e.g. "maltodextrin_de21"
  std::string description;  // what the material is
  std::string citation;     // the main source of its values
  std::vector<MaterialProperty> properties;
  const MaterialProperty* find(const std::string& property) const;  // null if the material has no such value
};

const std::vector<Material>& material_catalogue();
// The material called `name`; a ConfigError names the value and lists the catalogue's names otherwise.
const Material& find_material(const std::string& name);
// Whether `property` is a bulk property of the solid that only the particle system declares.
bool particle_system_property(const std::string& property);
// The property a parameter's local name stands for ("agg_Tg_solid" -> "Tg_solid"), or "" when none does.
std::string material_property_of(const std::string& param, bool particle_system);

class Flowsheet;
// Sets every parameter the material describes (its value and the source shown by `describe`), and returns the
// qualified names of the parameters the catalogue knows but this material does not give. `where` prefixes errors.
std::vector<std::string> apply_material(Flowsheet& fs, const Material& m, const std::string& where);

}  // namespace granuflow
