#include "granuflow/materials.hpp"

#include <algorithm>
#include <set>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"

namespace granuflow {

namespace {

// The values below are those the cited sources print, converted to SI; nothing is estimated here. A property a
// source does not give is absent, and a scene naming the material must then supply it (apply_material).
std::vector<Material> build_catalogue() {
  std::vector<Material> c;
  const std::string t6 = "paper 001, Table 6", t7 = "paper 001, Table 7", t8 = "paper 001, Table 8",
                    t9 = "paper 001, Table 9";
  c.push_back({"maltodextrin_de21",
               "food-grade maltodextrin from potato starch (Avebe MD20P, about 19 wt% dextrose), the solid of paper "
               "001's agglomeration experiments",
               "paper 001 (Stoeckl, Bellinghausen, Heinrich), section 2.1 and Tables 6-9",
               {
                   {"rho_s", 1545.0, "kg/m3", t6, "skeletal density"},
                   {"eps_intra", 0.3, "-", t7, "intra-particle void fraction of the primary particles"},
                   {"rho_p", 900.0, "kg/m3", t9, "particle density of the wetting closures"},
                   {"cp_s", 1220.0, "J/(kg K)", t6, "specific heat capacity"},
                   {"Tg_solid", 440.15, "K", t9, "glass transition temperature of the dry solid (167 degC)"},
                   {"gt_k", 6.4, "-", t9, "Gordon-Taylor constant against water"},
                   {"sticky_offset", 20.0, "K", t9, "sticky point above the glass transition"},
                   {"sticky_slope", 8.733, "K", t9, "width of the sticky transition"},
                   {"bet_mm", 0.037, "kg/kg", t8, "BET monolayer moisture at 20 degC"},
                   {"bet_n", 11.9, "-", t8, "BET number of layers at 20 degC"},
                   {"X_cr", 0.07, "kg/kg", t8, "critical moisture content of the drying curve"},
               }});
  c.push_back({"gamma_alumina",
               "porous gamma-Al2O3 granules, the cores of paper 003's layering and breakage experiments",
               "paper 003 (Peglow, Antonyuk, Jacob, Palzer, Heinrich, Tsotsas), sections 7.3, 7.5 and 7.6",
               {
                   {"e_restitution", 0.8, "-", "paper 003, section 7.5.4",
                    "coefficient of restitution, particle-particle and particle-wall (measured)"},
               }});
  c.push_back({"sodium_benzoate",
               "sodium benzoate (C7H5NaO2), the layer sprayed as a 30 wt% solution in paper 003, Tables 7.6 and 7.7",
               "PubChem CID 517055 (density); paper 003, section 7.3 (strength)",
               {
                   {"rho_s", 1440.0, "kg/m3", "PubChem CID 517055: 1.44 g/cm3 (crystal structures give up to 1.50)",
                    "density of the solid"},
                   {"sigma_compressive", 10.6e6, "Pa", "paper 003, section 7.3",
                    "mean compressive strength of sprayed granules, all size fractions"},
                   {"p_yield", 113e6, "Pa", "paper 003, section 7.3", "contact yield pressure, independent of size"},
               }});
  return c;
}

const std::set<std::string>& particle_properties() {
  static const std::set<std::string> p = {"rho_s", "eps_intra", "rho_p", "cp_s"};
  return p;
}

std::set<std::string> catalogue_properties() {
  std::set<std::string> all;
  for (const Material& m : material_catalogue())
    for (const MaterialProperty& p : m.properties) all.insert(p.name);
  return all;
}

}  // namespace

const MaterialProperty* Material::find(const std::string& property) const {
  for (const MaterialProperty& p : properties)
    if (p.name == property) return &p;
  return nullptr;
}

const std::vector<Material>& material_catalogue() {
  static const std::vector<Material> c = build_catalogue();
  return c;
}

const Material& find_material(const std::string& name) {
  std::string names;
  for (const Material& m : material_catalogue()) {
    if (m.name == name) return m;
    names += (names.empty() ? "" : ", ") + m.name;
  }
  throw ConfigError("material '" + shown(name) + "' is not in the catalogue; known: " + names +
                    " (granuflow materials lists them)");
}

bool particle_system_property(const std::string& property) { return particle_properties().count(property) > 0; }

std::string material_property_of(const std::string& param, bool particle_system) {
  static const std::set<std::string> all = catalogue_properties();
  // A kernel's parameters carry its mechanism's prefix (agg_) in every unit.
  const std::string bare = param.rfind("agg_", 0) == 0 ? param.substr(4) : param;
  if (!all.count(bare)) return "";
  if (particle_system_property(bare) != particle_system) return "";
  if (particle_system && bare != param) return "";
  return bare;
}

std::vector<std::string> apply_material(Flowsheet& fs, const Material& m, const std::string& where) {
  std::vector<std::string> missing;
  const std::string at = where.empty() ? "" : where + ": ";
  const auto& units = fs.units();
  for (const std::string& q : fs.param_names()) {
    const int id = fs.param_id(q);
    const int u = fs.param_location(id).first;
    const bool particles = units[static_cast<size_t>(u)].unit->type() == "particles";
    const std::string prop = material_property_of(fs.param_spec(id).name, particles);
    if (prop.empty()) continue;
    const MaterialProperty* p = m.find(prop);
    if (!p) {
      missing.push_back(q);
      continue;
    }
    if (fs.param_spec(id).unit != p->unit)
      throw ConfigError(at + "material " + m.name + " gives " + prop + " in " + p->unit + ", but " + q + " is in " +
                        fs.param_spec(id).unit);
    try {
      fs.set_param_default(id, p->value, "material " + m.name + ": " + p->source);
    } catch (const ConfigError& e) {
      throw ConfigError(at + "material " + m.name + " sets " + q + ": " + e.what());
    }
  }
  return missing;
}

}  // namespace granuflow
