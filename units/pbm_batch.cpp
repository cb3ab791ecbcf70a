// Batch population balance (paper 001, Eq. (20), without flows):
//     dN_i/dt = aggregation_i(N) + breakage_i(N) + growth_i(N),     i = 0 .. n-1,
// on a grid in particle volume (kernels/discretization/grid.hpp), each mechanism a physical kernel plus a
// numerical scheme chosen by name in the settings; a mechanism not named has no states, parameters or cost.
// What leaves the grid is integrated in book-keeping states (number/volume above, volume below) and either
// removed from the population (outside = remove) or put back into the first/last class with its volume
// (outside = fold, paper 001's choice). Growth's created volume is integrated too, so the mass balance
// closes to round-off and is reported.
//
// Numbers are absolute particle counts (states N_<i>, unit "-", absolute tolerance atol * number_scale).
// Kernels that read only sizes and parameters are evaluated in configure() and again only when one of their
// parameter values changes (a time-dependent input); the Jacobian is analytic unless a kernel reads N itself.
#include "pbm_batch.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "granuflow/errors.hpp"
#include "granuflow/flowsheet.hpp"
#include "kernels/discretization/grid.hpp"
#include "kernels/discretization/initial_distribution.hpp"
#include "kernels/discretization/psd.hpp"
#include "kernels/registry.hpp"
#include "size_grid_settings.hpp"

namespace granuflow::units {
namespace {

using namespace kernels;

constexpr const char* kNone = "none";
enum class Outside { kRemove, kFold };
enum class Initial { kExponential, kLognormalMass };

// A physical kernel and where its parameters sit in the unit's parameter vector.
template <class K>
struct Plugin {
  std::unique_ptr<K> kernel;
  int first = 0;  // index of its first parameter
  int count = 0;
  explicit operator bool() const { return kernel != nullptr; }
};

// Per scalar type scratch space of the residual (the unit is evaluated by one solver at a time).
template <class T>
struct Scratch {
  std::vector<T> rates, beta, sel, frag, sn, shape, amount;
  std::vector<T> field[4];  // moisture, spot moisture, temperature, liquid fraction
};

bool has_derivative(const double*, int, int) { return false; }
bool has_derivative(const Jet* p, int first, int count) {
  for (int k = first; k < first + count; ++k)
    if (!p[k].v.isZero()) return true;
  return false;
}

void to_jets(const std::vector<double>& v, std::vector<Jet>& out) {
  out.resize(v.size());
  for (size_t k = 0; k < v.size(); ++k) out[k] = Jet(v[k]);
}

std::vector<std::string> with_none(std::vector<std::string> names) {
  names.insert(names.begin(), kNone);
  return names;
}

class PbmBatch : public UnitBase<PbmBatch> {
 public:
  std::string type() const override { return "pbm_batch"; }
  void declare(UnitSpec& s, Settings& st) override;
  void configure(const UnitSpec& spec, const double* p) override;
  bool jacobian(const Ctx<double>& c, double cj, JacobianSink& sink) const override;
  void report(const Ctx<double>& c, double* out) const override;

  template <class T>
  Status eval(const Ctx<T>& c) const;
  template <class T>
  void init(InitCtx<T>& c) const;

 private:
  void declare_grid(Settings& st);
  template <class K>
  Plugin<K> plugin(UnitSpec& s, Settings& st, const Registry<K>& reg, const std::string& name,
                   const std::string& prefix);
  template <class T>
  ClassState<T> class_state(const T* N, const T* p, Scratch<T>& w) const;
  void refresh(const double* p) const;
  template <class T>
  bool field_derivative(const T* p) const {
    for (int f : p_field_)
      if (f >= 0 && has_derivative(p, f, 1)) return true;
    return false;
  }
  template <class T>
  const T* beta(const ClassState<T>& cs, const T* p, Scratch<T>& w) const;
  template <class T>
  void breakage(const ClassState<T>& cs, const T* N, const T* p, Scratch<T>& w, T* rates) const;
  template <class T>
  GrowthTerms<T> growth_terms(const T* p, Scratch<T>& w) const;
  template <class T>
  void fold(T* rates) const;
  template <class T>
  Scratch<T>& scratch() const {
    if constexpr (std::is_same_v<T, double>)
      return sd_;
    else
      return sj_;
  }

  std::unique_ptr<Grid> grid_;
  int n_ = 0;
  Outside outside_ = Outside::kRemove;
  Initial initial_ = Initial::kExponential;
  Binning binning_ = Binning::kMoments;
  int p_rho_ = 0, p_init_ = 0;  // rho, then the initial distribution's parameters
  int p_field_[4] = {-1, -1, -1, -1};
  ClassNeeds needs_;

  Plugin<AggregationKernel> agg_;
  std::unique_ptr<AggregationScheme> agg_scheme_;
  Plugin<SelectionRate> sel_;
  Plugin<FragmentDistribution> frag_;
  std::unique_ptr<BreakageScheme> brk_scheme_;
  Plugin<GrowthLaw> growth_;
  std::unique_ptr<FvGrowth> growth_scheme_;

  // Own state indices of the book-keeping states (-1 when the mechanisms cannot produce them).
  int s_outside_[kOutsideRows] = {-1, -1, -1};
  int s_grown_ = -1;
  double volume0_ = 0;  // on-grid volume at t = 0, m^3

  // Kernel values for the parameter values in snapshot_ (double path and Jets without parameter derivatives).
  mutable std::vector<double> snapshot_;
  mutable std::vector<double> beta_, sel_rate_, frag_matrix_;
  mutable std::vector<Jet> beta_jet_, sel_jet_, frag_jet_;
  mutable std::vector<double> jac_, dw_, pvals_, jet_values_;
  mutable Scratch<double> sd_;
  mutable Scratch<Jet> sj_;
};

// ---------------------------------------------------------------- declare

void PbmBatch::declare_grid(Settings& st) {
  const std::string kind = st.get_choice("grid", "geometric", {"geometric", "log_diameter"},
                                         "geometric in volume with ratio 2^(1/q), or log-spaced diameter pivots");
  if (kind == "geometric") {
    const long q = st.get_int("q", 2, 1, 64, "classes per doubling of the particle volume (ratio 2^(1/q))");
    const double v_min = st.get_real("v_min", std::exp2(-12.0), 1e-30, 1e6, "lowest volume edge, m3");
    const long classes = st.get_int("classes", 27 * q, 2, 2000, "number of classes");
    grid_ = std::make_unique<Grid>(Grid::geometric(v_min, static_cast<int>(q), static_cast<int>(classes)));
  } else {
    const double d_min = st.get_real("d_min", 50e-6, 1e-9, 1.0, "smallest pivot diameter, m");
    const double d_max = st.get_real("d_max", 1000e-6, 1e-9, 1.0, "largest pivot diameter, m");
    const long classes = st.get_int("classes", 10, 2, 2000, "number of classes");
    if (!(d_max > d_min))
      throw ConfigError(violation(st.where() + ".d_max", d_max, "m", "d_max > d_min (" + fmt_num(d_min) + " m)"));
    grid_ = std::make_unique<Grid>(Grid::from_diameter_pivots(log_spaced(d_min, d_max, static_cast<int>(classes))));
  }
  n_ = grid_->size();
}

template <class K>
Plugin<K> PbmBatch::plugin(UnitSpec& s, Settings& st, const Registry<K>& reg, const std::string& name,
                           const std::string& prefix) {
  Plugin<K> pl;
  if (name == kNone) return pl;
  pl.kernel = reg.create(name, st.where());
  pl.kernel->declare(st, prefix);
  pl.first = static_cast<int>(s.params().size());
  for (ParamSpec spec : pl.kernel->params()) {
    spec.name = prefix + spec.name;
    s.add_param(std::move(spec));
  }
  pl.count = static_cast<int>(s.params().size()) - pl.first;
  const ClassNeeds k = pl.kernel->needs();
  needs_.number |= k.number, needs_.moisture |= k.moisture, needs_.spot_moisture |= k.spot_moisture;
  needs_.temperature |= k.temperature, needs_.liquid_fraction |= k.liquid_fraction;
  return pl;
}

void PbmBatch::declare(UnitSpec& s, Settings& st) {
  const auto& reg = registries();
  declare_grid(st);
  outside_ = st.get_choice("outside", "remove", {"remove", "fold"},
                           "particles leaving the grid: removed (tracked) or kept in the end class with their "
                           "volume (paper 001)") == "fold"
                 ? Outside::kFold
                 : Outside::kRemove;
  const double number_scale = st.get_real("number_scale", 1.0, 1e-30, 1e30,
                                          "typical particle number; absolute tolerance = atol * number_scale");
  initial_ = st.get_choice("initial", "exponential", {"exponential", "lognormal_mass"}, "initial distribution") ==
                     "exponential"
                 ? Initial::kExponential
                 : Initial::kLognormalMass;
  binning_ = binning_from_string(st.get_choice("initial_binning", "moments", {"moments", "number", "mass"},
                                               "how cell integrals go on the pivots"));

  p_rho_ = s.add_param(
      {"rho", "kg/m3", 1000.0, 1e-3, 1e5, "particle density (mass <-> volume)", "material property (user)"});
  p_init_ = static_cast<int>(s.params().size());
  if (initial_ == Initial::kExponential) {
    s.add_param({"N0", "-", 1.0, 0.0, 1e30, "initial particle number", "docs/verification.md"});
    s.add_param({"v0", "m3", 1.0, 1e-30, 1e6, "initial mean particle volume", "docs/verification.md"});
  } else {
    s.add_param({"mass0", "kg", 1.0, 0.0, 1e6, "initial particle mass", "initial state (user)"});
    s.add_param({"d50_3", "m", 200e-6, 1e-9, 1.0, "initial mass median diameter", "docs/paper001_decisions.md"});
    s.add_param(
        {"sigma_g", "-", 1.5, 1.0001, 10.0, "initial geometric standard deviation", "docs/paper001_decisions.md"});
  }

  const std::string agg = st.get_choice("aggregation", kNone, with_none(reg.aggregation.names()), "aggregation kernel");
  agg_ = plugin(s, st, reg.aggregation, agg, "agg_");
  if (agg_)
    agg_scheme_ = reg.aggregation_schemes.create(
        st.get_choice("aggregation_scheme", "cell_average", reg.aggregation_schemes.names(), "aggregation scheme"),
        st.where());
  const std::string sel = st.get_choice("breakage", kNone, with_none(reg.selection.names()), "breakage selection rate");
  sel_ = plugin(s, st, reg.selection, sel, "sel_");
  if (sel_) {
    frag_ =
        plugin(s, st, reg.fragments,
               st.get_choice("fragments", "uniform_binary", reg.fragments.names(), "fragment distribution"), "frag_");
    brk_scheme_ = reg.breakage_schemes.create(
        st.get_choice("breakage_scheme", "cell_average", reg.breakage_schemes.names(), "breakage scheme"), st.where());
  }
  const std::string gr = st.get_choice("growth", kNone, with_none(reg.growth.names()), "growth law");
  growth_ = plugin(s, st, reg.growth, gr, "growth_");
  if (growth_)
    growth_scheme_ = reg.growth_schemes.create(
        st.get_choice("growth_scheme", "fv_koren", reg.growth_schemes.names(), "growth scheme"), st.where());

  // Per-class state the kernels read; a batch unit has it as (uniform) parameters.
  const std::string batch_value = "batch value for every class (user)";
  if (needs_.moisture)
    p_field_[0] = s.add_param({"X", "kg/kg", 0.0, 0.0, 10.0, "liquid loading of the particles", batch_value});
  if (needs_.spot_moisture)
    p_field_[1] = s.add_param({"X_spot", "kg/kg", 0.0, 0.0, 10.0, "moisture of the wet spots", "paper 001, Eq. (55)"});
  if (needs_.temperature)
    p_field_[2] = s.add_param({"T", "K", 293.15, 200.0, 700.0, "particle temperature", batch_value});
  if (needs_.liquid_fraction)
    p_field_[3] = s.add_param({"liquid_fraction", "-", 0.0, 0.0, 1.0, "liquid volume / particle volume",
                               "paper 002, Eq. (13); " + batch_value});

  for (int i = 0; i < n_; ++i) s.add_state("N_" + std::to_string(i), StateKind::Differential, "-", number_scale);
  const double v_mid = grid_->pivot(n_ / 2);
  if (agg_ || growth_) {
    s_outside_[kNumberAbove] = s.add_state("number_above", StateKind::Differential, "-", number_scale);
    s_outside_[kVolumeAbove] = s.add_state("volume_above", StateKind::Differential, "m3", number_scale * v_mid);
  }
  if (sel_ || growth_)
    s_outside_[kVolumeBelow] = s.add_state("volume_below", StateKind::Differential, "m3", number_scale * v_mid);
  if (growth_) s_grown_ = s.add_state("volume_grown", StateKind::Differential, "m3", number_scale * v_mid);

  s.add_output("number", "-");
  s.add_output("mass", "kg");
  s.add_output("d10_3", "m");
  s.add_output("d50_3", "m");
  s.add_output("d90_3", "m");
  s.add_output("mass_above", "kg");
  s.add_output("mass_below", "kg");
  s.add_output("mass_grown", "kg");
  s.add_output("mass_balance", "-");
}

// ---------------------------------------------------------------- configure and kernel values

void PbmBatch::configure(const UnitSpec& spec, const double* p) {
  const int np = static_cast<int>(spec.params().size());
  pvals_.assign(p, p + np);
  ClassState<double> cs = class_state<double>(nullptr, p, sd_);
  const std::string where = "unit pbm_batch";
  const std::pair<const KernelBase*, int> kernels[] = {{agg_.kernel.get(), agg_.first},
                                                       {sel_.kernel.get(), sel_.first},
                                                       {frag_.kernel.get(), frag_.first},
                                                       {growth_.kernel.get(), growth_.first}};
  for (const auto& [k, first] : kernels)
    if (k) k->check(cs, p + first, where);
  if (agg_) agg_scheme_->setup(*grid_);
  if (growth_) growth_scheme_->setup(*grid_);
  snapshot_.clear();
  refresh(p);
  std::vector<double> x0(spec.states().size());
  InitCtx<double> ic{p, x0.data()};
  init(ic);
  volume0_ = volume_moment(*grid_, x0.data(), 1);
}

template <class T>
ClassState<T> PbmBatch::class_state(const T* N, const T* p, Scratch<T>& w) const {
  ClassState<T> cs;
  cs.n = n_;
  cs.volume = grid_->pivots().data();
  cs.diameter = grid_->diameter_pivots().data();
  cs.number = N;
  const T** fields[4] = {&cs.moisture, &cs.spot_moisture, &cs.temperature, &cs.liquid_fraction};
  for (int f = 0; f < 4; ++f)
    if (p_field_[f] >= 0) {
      w.field[f].assign(n_, p[p_field_[f]]);
      *fields[f] = w.field[f].data();
    }
  return cs;
}

// Re-evaluates the state-independent kernels when a parameter value changed since the last evaluation.
void PbmBatch::refresh(const double* p) const {
  const size_t np = pvals_.size();
  if (snapshot_.size() == np && std::equal(p, p + np, snapshot_.begin())) return;
  snapshot_.assign(p, p + np);
  auto& w = sd_;
  const ClassState<double> cs = class_state<double>(nullptr, p, w);
  if (agg_ && !needs_.number) {
    beta_.resize(size_t(n_) * n_);
    agg_.kernel->evaluate(cs, p + agg_.first, beta_.data());
    to_jets(beta_, beta_jet_);
  }
  if (sel_) {
    if (!needs_.number) {
      sel_rate_.resize(n_);
      sel_.kernel->evaluate(cs, p + sel_.first, sel_rate_.data());
      to_jets(sel_rate_, sel_jet_);
    }
    frag_matrix_.resize(size_t(n_ + kOutsideRows) * n_);
    brk_scheme_->build(*grid_, *frag_.kernel, p + frag_.first, frag_matrix_.data());
    to_jets(frag_matrix_, frag_jet_);
  }
}

// beta for this evaluation: the cached matrix unless the kernel reads N or a parameter carries a derivative.
template <class T>
const T* PbmBatch::beta(const ClassState<T>& cs, const T* p, Scratch<T>& w) const {
  const bool fresh = needs_.number || has_derivative(p, agg_.first, agg_.count) || field_derivative(p);
  if (fresh) {
    w.beta.resize(size_t(n_) * n_);
    agg_.kernel->evaluate(cs, p + agg_.first, w.beta.data());
    return w.beta.data();
  }
  if constexpr (std::is_same_v<T, double>)
    return beta_.data();
  else
    return beta_jet_.data();
}

template <class T>
void PbmBatch::breakage(const ClassState<T>& cs, const T* N, const T* p, Scratch<T>& w, T* rates) const {
  const T* S;
  if (needs_.number || has_derivative(p, sel_.first, sel_.count) || field_derivative(p)) {
    w.sel.resize(n_);
    sel_.kernel->evaluate(cs, p + sel_.first, w.sel.data());
    S = w.sel.data();
  } else if constexpr (std::is_same_v<T, double>) {
    S = sel_rate_.data();
  } else {
    S = sel_jet_.data();
  }
  const T* A;
  if (has_derivative(p, frag_.first, frag_.count)) {
    w.frag.resize(size_t(n_ + kOutsideRows) * n_);
    brk_scheme_->build(*grid_, *frag_.kernel, p + frag_.first, w.frag.data());
    A = w.frag.data();
  } else if constexpr (std::is_same_v<T, double>) {
    A = frag_matrix_.data();
  } else {
    A = frag_jet_.data();
  }
  w.sn.resize(n_);
  for (int k = 0; k < n_; ++k) w.sn[k] = S[k] * N[k];
  for (int r = 0; r < n_ + kOutsideRows; ++r) {
    const T* a = A + size_t(r) * n_;
    T acc(0.0);
    // Fragments land at or below the parent's pivot: class row r only sees parents k >= r.
    for (int k = r < n_ ? r : 0; k < n_; ++k) acc += a[k] * w.sn[k];
    rates[r] += acc;
  }
}

template <class T>
GrowthTerms<T> PbmBatch::growth_terms(const T* p, Scratch<T>& w) const {
  const int nf = growth_scheme_->faces(), K = growth_.kernel->terms();
  w.shape.resize(size_t(K) * nf);
  w.amount.resize(K);
  growth_.kernel->evaluate(growth_scheme_->face_diameters().data(), nf, p + growth_.first, w.shape.data(),
                           w.amount.data());
  return {K, w.shape.data(), w.amount.data(), growth_.kernel->volume_normalized()};
}

template <class T>
void PbmBatch::fold(T* rates) const {
  if (outside_ != Outside::kFold) return;
  rates[0] += rates[n_ + kVolumeBelow] / grid_->pivot(0);
  rates[n_ - 1] += rates[n_ + kVolumeAbove] / grid_->pivot(n_ - 1);
}

// ---------------------------------------------------------------- residual, Jacobian, initial values

template <class T>
Status PbmBatch::eval(const Ctx<T>& c) const {
  Scratch<T>& w = scratch<T>();
  const T* N = c.x + c.offset;
  if constexpr (std::is_same_v<T, double>) {
    refresh(c.p);
  } else {
    jet_values_.resize(pvals_.size());
    for (size_t k = 0; k < jet_values_.size(); ++k) jet_values_[k] = c.p[k].a;
    refresh(jet_values_.data());
  }
  w.rates.assign(n_ + kOutsideRows, T(0.0));
  const ClassState<T> cs = class_state(N, c.p, w);
  if (agg_) agg_scheme_->add_rates(N, beta(cs, c.p, w), w.rates.data());
  if (sel_) breakage(cs, N, c.p, w, w.rates.data());
  T created(0.0);
  if (growth_) created = growth_scheme_->add_rates(N, growth_terms(c.p, w), w.rates.data());
  fold(w.rates.data());
  for (int i = 0; i < n_; ++i) c.res(i) = c.xd(i) - w.rates[i];
  for (int r = 0; r < kOutsideRows; ++r)
    if (s_outside_[r] >= 0) c.res(s_outside_[r]) = c.xd(s_outside_[r]) - w.rates[n_ + r];
  if (s_grown_ >= 0) c.res(s_grown_) = c.xd(s_grown_) - created;
  return Status::kOk;
}

bool PbmBatch::jacobian(const Ctx<double>& c, double cj, JacobianSink& sink) const {
  if (needs_.number) return false;  // a kernel that reads N: forward AD
  const int n = n_, rows = n_ + kOutsideRows;
  const double* N = c.x + c.offset;
  refresh(c.p);
  jac_.assign(size_t(rows) * n, 0.0);
  double* J = jac_.data();
  if (agg_) agg_scheme_->add_jacobian(N, beta_.data(), J);
  if (sel_)
    for (int r = 0; r < rows; ++r)
      for (int k = 0; k < n; ++k) J[size_t(r) * n + k] += frag_matrix_[size_t(r) * n + k] * sel_rate_[k];
  dw_.assign(n, 0.0);
  if (growth_) growth_scheme_->add_jacobian(N, growth_terms(c.p, sd_), J, dw_.data());
  if (outside_ == Outside::kFold)
    for (int l = 0; l < n; ++l) {
      J[l] += J[size_t(n + kVolumeBelow) * n + l] / grid_->pivot(0);
      J[size_t(n - 1) * n + l] += J[size_t(n + kVolumeAbove) * n + l] / grid_->pivot(n - 1);
    }
  // F = N' - rates(N): dF/dN + cj dF/dN' = cj I - d rates / dN.
  auto emit = [&](int row, const double* d) {
    sink.add(row, c.offset + row, cj);
    for (int l = 0; l < n; ++l)
      if (d[l] != 0.0) sink.add(row, c.offset + l, -d[l]);
  };
  for (int i = 0; i < n; ++i) emit(i, J + size_t(i) * n);
  for (int r = 0; r < kOutsideRows; ++r)
    if (s_outside_[r] >= 0) emit(s_outside_[r], J + size_t(n + r) * n);
  if (s_grown_ >= 0) emit(s_grown_, dw_.data());
  return true;
}

template <class T>
void PbmBatch::init(InitCtx<T>& c) const {
  std::vector<T> number(n_), volume(n_);
  const T* p = c.p + p_init_;
  if (initial_ == Initial::kExponential)
    exponential_cells(*grid_, p[0], p[1], number.data(), volume.data());
  else
    lognormal_mass_cells(*grid_, T(p[0] / c.p[p_rho_]), p[1], p[2], number.data(), volume.data());
  bin_cells(*grid_, binning_, number.data(), volume.data(), c.x0);
  for (int r = 0; r < kOutsideRows; ++r)
    if (s_outside_[r] >= 0) c.x0[s_outside_[r]] = T(0.0);
  if (s_grown_ >= 0) c.x0[s_grown_] = T(0.0);
}

void PbmBatch::report(const Ctx<double>& c, double* out) const {
  const double* N = c.x + c.offset;
  const double rho = c.p[p_rho_];
  auto state = [&](int s) { return s >= 0 ? c.x_(s) : 0.0; };
  const double volume = volume_moment(*grid_, N, 1);
  const double above = state(s_outside_[kVolumeAbove]), below = state(s_outside_[kVolumeBelow]);
  const double grown = state(s_grown_);
  const double outside = outside_ == Outside::kRemove ? above + below : 0.0;
  out[0] = volume_moment(*grid_, N, 0);
  out[1] = rho * volume;
  out[2] = characteristic_diameter(*grid_, N, 0.1);
  out[3] = characteristic_diameter(*grid_, N, 0.5);
  out[4] = characteristic_diameter(*grid_, N, 0.9);
  out[5] = rho * above;
  out[6] = rho * below;
  out[7] = rho * grown;
  out[8] = volume0_ > 0 ? (volume + outside - grown - volume0_) / volume0_ : 0.0;
}

}  // namespace

void register_pbm_batch(Registry<Unit>& r) {
  r.add("pbm_batch", "batch population balance: aggregation, breakage, growth by named kernels and schemes",
        [] { return std::make_unique<PbmBatch>(); });
}

}  // namespace granuflow::units
