// The population engine's set-up: the mechanisms chosen by name and their parameters (declare), and the tables of
// the kernels' values, rebuilt when a kernel parameter changes (refresh). The rates are in population_rates.cpp and
// population_breakage.cpp, the Jacobians in population_jacobian.cpp.
#include <algorithm>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "population/population_work.hpp"
#include "registry.hpp"

namespace granuflow::kernels {

namespace {
constexpr const char* kNone = "none";

std::vector<std::string> with_none(std::vector<std::string> names) {
  names.insert(names.begin(), kNone);
  return names;
}

void to_jets(const std::vector<double>& v, std::vector<Jet>& out) {
  out.resize(v.size());
  for (size_t k = 0; k < v.size(); ++k) out[k] = Jet(v[k]);
}
}  // namespace

const char* field_name(Field f) {
  static const char* names[kFields] = {"moisture", "spot_moisture", "temperature", "liquid_fraction",
                                       "wetted_fraction"};
  return names[static_cast<int>(f)];
}

bool same_parameters(std::vector<Jet>& memo, const Jet* p, int first, int count) {
  bool same = static_cast<int>(memo.size()) == count;
  for (int k = 0; k < count && same; ++k) same = memo[k].a == p[first + k].a && memo[k].v == p[first + k].v;
  if (!same) memo.assign(p + first, p + first + count);
  return same;
}

void make_jets(Population::Work& w) {
  if (w.jets) return;
  to_jets(w.Kh, w.Kh_jet), to_jets(w.A, w.A_jet), to_jets(w.BN, w.BN_jet), to_jets(w.BQ, w.BQ_jet);
  w.jets = true;
}

Population::Population() = default;
Population::~Population() = default;
Population::Population(Population&&) noexcept = default;
Population& Population::operator=(Population&&) noexcept = default;

template <class K>
Population::Plugin<K> Population::plugin(UnitSpec& s, Settings& st, const Registry<K>& reg, const std::string& name,
                                         const std::string& param_prefix, const std::string& setting_prefix) {
  Plugin<K> pl;
  if (name == kNone) return pl;
  pl.kernel = reg.create(name, st.where());
  pl.kernel->declare(st, setting_prefix);
  pl.first = static_cast<int>(s.params().size());
  for (ParamSpec spec : pl.kernel->params()) {
    spec.name = param_prefix + spec.name;
    if (s.param_index(spec.name) >= 0)
      throw ConfigError(st.where() + ": parameter '" + spec.name + "' of " + name +
                        " is declared twice in this unit (two mechanisms with the same parameter name)");
    s.add_param(std::move(spec));
  }
  pl.count = static_cast<int>(s.params().size()) - pl.first;
  for (int k = pl.first; k < pl.first + pl.count; ++k) kernel_params_.push_back(k);
  needs_ |= pl.kernel->needs();
  return pl;
}

void Population::declare(UnitSpec& s, Settings& st, std::shared_ptr<const Grid> grid, const PopulationOptions& o) {
  const auto& reg = registries();
  grid_ = std::move(grid);
  n_ = grid_->size();
  property_names_ = o.properties;
  if (properties() > kMaxProperties)
    throw std::logic_error("a population carries at most " + std::to_string(kMaxProperties) + " properties per class");
  outside_ = st.get_choice("outside", o.outside == Outside::kFold ? "fold" : "remove", {"fold", "remove"},
                           "particles leaving the grid: kept in the end class with their volume (fold, paper 001) "
                           "or removed and counted (remove)") == "fold"
                 ? Outside::kFold
                 : Outside::kRemove;
  const std::string agg =
      st.get_choice("aggregation", o.aggregation, with_none(reg.aggregation.names()), "aggregation kernel");
  agg_ = plugin(s, st, reg.aggregation, agg, o.agg_prefix, o.agg_settings);
  if (agg_.kernel) {
    agg_scheme_ = reg.aggregation_schemes.create(st.get_choice("aggregation_scheme", o.aggregation_scheme,
                                                               reg.aggregation_schemes.names(), "aggregation scheme"),
                                                 st.where());
    agg_scheme_->setup(*grid_);
  }
  const std::string sel =
      st.get_choice("breakage", o.breakage, with_none(reg.selection.names()), "breakage selection rate");
  sel_ = plugin(s, st, reg.selection, sel, o.sel_prefix, o.sel_settings);
  if (sel_.kernel) {
    frag_ = plugin(s, st, reg.fragments,
                   st.get_choice("fragments", o.fragments, reg.fragments.names(), "fragment distribution"),
                   o.frag_prefix, o.frag_settings);
    brk_scheme_ = reg.breakage_schemes.create(
        st.get_choice("breakage_scheme", o.breakage_scheme, reg.breakage_schemes.names(), "breakage scheme"),
        st.where());
  }
  const std::string gr =
      o.growth.empty() ? kNone : st.get_choice("growth", o.growth, with_none(reg.growth.names()), "growth law");
  growth_ = plugin(s, st, reg.growth, gr, o.growth_prefix, o.growth_settings);
  if (growth_.kernel) {
    growth_scheme_ = reg.growth_schemes.create(
        st.get_choice("growth_scheme", o.growth_scheme, reg.growth_schemes.names(), "growth scheme"), st.where());
    growth_scheme_->setup(*grid_);
  }
  field_index_.clear();
  for (int f = 0; f < kFields; ++f)
    if (needs_.field(static_cast<Field>(f))) field_index_.push_back(f);
}

std::string Population::aggregation_evaluation(const Work& w) const {
  return !agg_.kernel ? "none" : agg_scheme_->evaluation(*w.agg);
}

Population::WorkPtr Population::make_work() const {
  WorkPtr w(new Work());
  if (agg_scheme_) w->agg = agg_scheme_->make_tables();
  return w;
}
void Population::WorkDeleter::operator()(Work* w) const { delete w; }

void Population::configure(Work& w, const double* p, const std::string& where) const {
  ClassState<double> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  const std::pair<const KernelBase*, int> kernels[] = {{agg_.kernel.get(), agg_.first},
                                                       {sel_.kernel.get(), sel_.first},
                                                       {frag_.kernel.get(), frag_.first},
                                                       {growth_.kernel.get(), growth_.first}};
  for (const auto& [k, first] : kernels)
    if (k) k->check(cs, p + first, where);
  w.fresh = false;
  w.kh_params.clear(), w.sel_params.clear(), w.frag_params.clear();
  refresh(w, p);
}

// Re-evaluates the tables when a kernel parameter value changed since the last evaluation (a time-dependent input,
// a calibration's step), each mechanism's only when one of its own parameters moved: the aggregation's pair
// coefficients and what its scheme derives from them (the scheme's grid-only tables were built in declare()), the
// breakage tables when the selection or fragment parameters moved. After configure() everything is rebuilt.
void Population::refresh(Work& w, const double* p) const {
  const size_t np = kernel_params_.size();
  const bool all = !w.fresh || w.snapshot.size() != np;
  auto owns = [](const auto& plugin, int i) { return i >= plugin.first && i < plugin.first + plugin.count; };
  bool moved = all, agg = all, brk = all;
  for (size_t k = 0; k < np && !all; ++k) {
    const int i = kernel_params_[k];
    if (w.snapshot[k] == p[i]) continue;
    moved = true;
    agg |= owns(agg_, i);
    brk |= owns(sel_, i) || owns(frag_, i);
  }
  if (!moved) return;
  w.snapshot.resize(np);
  for (size_t k = 0; k < np; ++k) w.snapshot[k] = p[kernel_params_[k]];
  w.fresh = true;
  w.jets = false;
  ClassState<double> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  if (agg_.kernel && agg) {
    w.K.resize(size_t(n_) * n_);
    agg_.kernel->factor(cs, p + agg_.first, w.K.data());
    pack_pairs(w.K, n_, w.Kh);
    agg_scheme_->refresh(*w.agg, {grid_.get(), properties(), &w.K, &w.Kh, agg_.kernel.get(), &cs, p + agg_.first});
  }
  if (sel_.kernel && brk) {
    brk_scheme_->matrix(*grid_, *frag_.kernel, p + frag_.first, frag_.count, w.A);
    if (!sel_.kernel->state_dependent()) {
      w.S.resize(n_);
      sel_.kernel->evaluate(cs, p + sel_.first, w.S.data());
      breakage_tables(*grid_, w.A.data(), w.S.data(), w.BN, w.BQ);
    }
  }
}

int Population::input_cols() const { return n_ * (1 + properties() + static_cast<int>(field_index_.size())); }

}  // namespace granuflow::kernels
