// Calibration of flowsheet parameters against batch experiments with Ceres, in stages (paper 001, Fig. 10:
// heat and mass transfer first, then size, then everything together; Table 5 standard deviations as weights).
//
// The loss of a stage is weighted least squares over experiments e, observables o of the stage and samples i:
//
//   C(θ) = ½ Σ_e Σ_o Σ_i r_eoi²,   r_eoi = (m_eoi(p(θ)) - d_eoi) / σ_eoi,
//
// m the model (a state, e.g. gas.T, or a reported output, e.g. bed.d50, at the sample time), d the data and
// σ = σ_abs, or σ = σ_rel |m| (SigmaBasis::kModel, default) or σ = σ_rel |d| (SigmaBasis::kData).
// With kModel the weights are fixed during each least-squares solve and re-taken at its optimum for another
// solve until they settle (iteratively reweighted least squares, `max_reweighting_passes`): the fixed point
// solves Σ (m - d) / σ² dm/dθ = 0, unbiased when the noise is proportional to the true value. Differentiating
// σ(m) inside the loss instead would bias m up by σ_rel². kData weights low measurements more and biases the
// fit low, by about 2 σ_rel² in the predicted quantity (shown by the synthetic test when asked for).
// θ are the stage's free parameters, each as given or as its natural logarithm (Transform::kLog), within
// bounds. The Jacobian ∂r/∂θ = ∂r/∂m · dm/dp · dp/dθ takes dm/dp from one IDAS forward-sensitivity solve per
// experiment and evaluation (states directly, reported outputs by output_sensitivities()); with
// JacobianMethod::kCentralDifferences (models without sensitivities) from 2 simulations per free parameter,
// and every report says which was used.
// At the optimum: covariance (JᵀJ)⁻¹ in θ (σ taken as known; multiplied by the reduced χ² only with
// scale_covariance), standard errors mapped to parameter units by the delta method, the correlation matrix,
// and identifiability flags: relative standard error above `rse_threshold`, |correlation| above
// `correlation_threshold`, a bound reached, or a loss profile that stays flat (Δχ² below `profile_delta_chi2`)
// up to a bound or `profile_max_offset` away. Profiles are computed for flagged parameters of the last stage.
//
// Experiment runs are solved in parallel on `num_threads` threads (Ceres evaluates the residual block of each
// experiment on its own thread); each experiment owns a clone of the scene. Failures are a CalibrationError
// (bad configuration: ConfigError), never an abort; a simulation failing at a trial point makes Ceres shrink
// its step.
#pragma once
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "granuflow/registry.hpp"
#include "granuflow/scene.hpp"

namespace granuflow {

enum class Transform { kNone, kLog };
std::string to_string(Transform t);
Transform transform_from_string(const std::string& s);  // "none" | "log"; ConfigError otherwise

enum class SigmaBasis { kModel, kData };
std::string to_string(SigmaBasis b);
SigmaBasis sigma_basis_from_string(const std::string& s);  // "model" | "data"

enum class JacobianMethod { kSensitivities, kCentralDifferences };
std::string to_string(JacobianMethod m);
JacobianMethod jacobian_method_from_string(const std::string& s);  // "sensitivities" | "central_differences"

// One measured quantity of one run, sampled in time. Exactly one of sigma_abs, sigma_rel is > 0.
// A measured size distribution is one observation per measured size: "unit.Q3(<size>)", e.g. "bed.Q3(500 um)",
// the cumulative mass fraction below that size (0..1) read from the unit's class masses as d50 is
// (src/size_fraction.hpp, docs/measured_psd.md), usually with its own sigma_abs.
struct Observation {
  std::string name;           // "unit.output" (reported), "unit.state" or "unit.Q3(size)"
  std::vector<double> t;      // s, increasing, >= 0
  std::vector<double> value;  // SI; NaN = not measured at that time
  double sigma_abs = 0.0;     // SI
  double sigma_rel = 0.0;     // fraction of the value (SigmaBasis says of which)
};

// One batch run: operating conditions and initial state as parameter values, and its observations.
struct Experiment {
  std::string name;
  std::vector<std::pair<std::string, double>> settings;  // "unit.param" -> SI value, applied over the scene
  double t_end = 0.0;                                    // s; 0: the last sample time
  std::vector<Observation> observations;
};

struct FreeParameter {
  std::string name;  // "unit.param"
  Transform transform = Transform::kNone;
  std::optional<double> lower, upper;  // SI; default: the declared bounds (kLog needs lower > 0)
  // The parameter is itself a logarithm (ln β0): its standard error is already relative. Default: name
  // starts with "ln_".
  std::optional<bool> logarithmic;
};

struct Stage {
  std::string name;
  std::vector<FreeParameter> free;
  std::vector<std::string> observables;  // observation names in the loss; empty: all
};

// Where a calibration is, for a progress display: reported on the calling thread after every Ceres iteration.
struct CalibrationProgress {
  std::string stage;  // the stage's name ("profile of NAME" while a parameter is profiled)
  int iteration = 0;  // Ceres' iteration within the current least-squares solve (0: its start)
  double cost = 0.0;  // ½χ² there
  long simulations = 0, sensitivity_solves = 0;  // of this least-squares solve so far
};

struct CalibrationOptions {
  // Ceres Levenberg-Marquardt, per stage.
  int max_iterations = 50;            // >= 1
  double function_tolerance = 1e-5;   // |Δcost| / cost at which a stage has converged, > 0 (1e-5 of a
                                      // χ²/2 near N/2: far below Δχ² = 1, above the integration noise)
  double gradient_tolerance = 1e-10;  // > 0
  double parameter_tolerance = 1e-6;  // |Δθ| / (|θ| + tol), > 0
  // Also converged when an accepted step lowers the cost ½χ² by less than this (absolute): the optimum is then
  // within about sqrt(4 x this) = 0.2 standard errors, and further steps only chase integration noise or
  // crawl along directions the data do not determine. >= 0 (0: off)
  double cost_change_tolerance = 0.01;
  // Levenberg-Marquardt starts with damping 1 / radius (Jacobi-scaled). Ceres' default 1e4 is nearly undamped
  // Gauss-Newton, whose first steps on ill-conditioned stages (k_evap against X_cr) are rejected one after
  // another, each costing a simulation per experiment. > 0
  double initial_trust_region_radius = 1e2;
  int num_threads = 1;  // experiments solved in parallel, >= 1
  SigmaBasis sigma_basis = SigmaBasis::kModel;
  int max_reweighting_passes = 4;       // kModel: least-squares solves per stage, >= 1
  double reweighting_tolerance = 0.02;  // kModel: stop when no σ changes by more than this fraction, >= 0
  JacobianMethod jacobian = JacobianMethod::kSensitivities;
  double fd_step = 1e-3;  // central differences: step in θ (times max(|θ|, 1) for kNone), > 0
  // Simulations inside the calibration.
  // Tolerances well below the measurement noise (1-11 %): the model error they leave (~1e-5 relative) is
  // hundreds of times smaller than the standard errors, and a sensitivity solve costs ~1.4x less than at 1e-6.
  double rtol = 1e-5;               // 0 < rtol < 1
  double atol = 1e-7;               // > 0 (times each state's scale)
  bool sens_error_control = false;  // sensitivities in IDAS's error test (SimOptions::sens_error_control)
  // Statistics at the optimum.
  bool scale_covariance = false;        // multiply the covariance by the reduced χ² (σ not trusted)
  double rse_threshold = 0.3;           // flag (and profile): relative standard error above this, > 0
  double correlation_threshold = 0.95;  // flag: |correlation| above this, in (0, 1]
  bool profile = true;                  // profile the loss over flagged parameters of the last stage
  double profile_delta_chi2 = 3.84;     // Δχ² of a 95 % interval (1 dof), > 0
  double profile_max_offset = 2.3;      // farthest profile point from the optimum in θ, in units of
                                        // max(SE_θ, 1) for kLog/logarithmic (2.3 = a factor of 10), else of SE
  int profile_max_points = 4;           // per side, >= 1
  // Flat regions of the loss (a start where no observable responds to a parameter, e.g. a penetration depth below
  // ~130 um where d50 does not move, stays there with a small gradient and reports success). At the end of every
  // stage a free parameter is flat when its curvature (JᵀJ)_kk, times the square of its span in θ, is below
  // flat_delta_chi2: moving it anywhere within its bounds would change χ² by less than that to second order.
  // The loss is then scanned over its bounds (flat_scan_points values evenly spaced in θ, the other parameters at
  // their estimates; 0: no scan), and a scan point, or a point of a profile, whose χ² lies more than
  // restart_delta_chi2 below the estimate's restarts the stage from it (at most max_restarts times per stage).
  // Failing that, the stage restarts from the edge of the flat region, where the loss starts to respond, unless a
  // later stage frees the parameter again (its descent then starts there, with its own data); such a parameter
  // goes on at its value from before the stage if the loss there is within restart_delta_chi2 of the estimate's.
  double flat_delta_chi2 = 0.01;    // > 0
  int flat_scan_points = 16;        // >= 0 (0: off; otherwise >= 3)
  double restart_delta_chi2 = 1.0;  // > 0
  int max_restarts = 2;             // >= 0
  // A sensitivity solve that fails is retried once with a tenth of the tolerance and at most 1/200 of the run per
  // step, then replaced by central differences of plain simulations; only when those fail too does the evaluation
  // fail (Ceres then shortens its step). The report counts the retries.
  // Called after every Ceres iteration (may be empty). It only watches: the estimates do not depend on it.
  std::function<void(const CalibrationProgress&)> progress;
  // Throws ConfigError naming the field, the value and the rule.
  void validate() const;
};

struct Estimate {
  std::string name;
  Transform transform = Transform::kNone;
  bool logarithmic = false;
  double start = 0.0, value = 0.0;     // SI
  double theta = 0.0, se_theta = 0.0;  // in the calibrated coordinate θ
  double se = 0.0;                     // SI (delta method); inf if the covariance is singular in this direction
  double rel_se = 0.0;                 // se/|value|; se_theta for kLog; se for logarithmic parameters
  double lower = 0.0, upper = 0.0;     // SI bounds used
  bool at_bound = false;
  bool identifiable = true;  // false: flagged, not reported as recovered
  std::string flag;          // why it is flagged ("" if not)
};

struct Profile {
  std::string name;                       // parameter
  std::vector<double> values;             // SI, increasing, including the optimum
  std::vector<double> delta_chi2;         // 2 (C(value) - C(optimum)), other free parameters re-optimized
  double lower_95 = 0.0, upper_95 = 0.0;  // where Δχ² crosses profile_delta_chi2 (bounds/limits if it never does)
  bool bounded_below = false, bounded_above = false;  // the crossing was found on that side
  bool linear_trustworthy = false;                    // Δχ² at ±2 SE_θ within a factor 2 of the linear 4
  long simulations = 0, sensitivity_solves = 0;
  std::string verdict;  // "identifiable" | "unidentifiable" | "nonlinear"
};

struct StageResult {
  std::string name;
  std::vector<std::string> observables;
  std::vector<Estimate> estimates;        // the free parameters, in stage order
  std::vector<double> covariance;         // row-major n x n, in θ
  std::vector<double> correlation;        // row-major n x n
  std::vector<double> iteration_costs;    // Ceres cost after each iteration (iteration 0 = start)
  double initial_cost = 0.0, cost = 0.0;  // ½ χ²
  long residuals = 0;
  double chi2_reduced = 0.0;   // 2 cost / (residuals - free parameters)
  int iterations = 0;          // Ceres iterations over all passes
  int passes = 0;              // least-squares solves (reweighting passes)
  double weight_change = 0.0;  // largest relative change of a σ in the last reweighting
  long simulations = 0, sensitivity_solves = 0;
  double wall_time_s = 0.0;
  std::string jacobian_method;  // "sensitivities" | "central_differences"
  std::string termination;      // Ceres: CONVERGENCE, NO_CONVERGENCE, FAILURE, ...
  std::string message;
  bool usable = false;
  std::vector<Profile> profiles;
  // At the estimate, in θ: the gradient of the cost ½χ², Jᵀr, and the curvature (JᵀJ)_kk of every free parameter
  // (χ² changes by about curvature Δθ² when θ_k alone moves by Δθ).
  std::vector<double> gradient, curvature;
  std::vector<std::string> flat;   // free parameters the loss does not respond to at the estimate (flat_delta_chi2)
  bool moved = true;               // some free parameter left its start
  int restarts = 0;                // restarts from a lower point of a scan or profile
  long sensitivity_retries = 0;    // failed sensitivity solves retried (smaller step, or central differences)
  std::vector<std::string> notes;  // what happened beyond the plain solve (restarts, flat parameters, retries)
};

struct CalibrationResult {
  std::vector<StageResult> stages;
  std::map<std::string, double> parameters;  // the start values, updated by every stage (SI)
  long simulations = 0, sensitivity_solves = 0;
  double wall_time_s = 0.0;
  std::string status = "ok";  // "ok" | "no_convergence" (a stage stopped without converging)
  std::string message;
  // What a user must know before trusting the estimates: a stage left in a flat region of the loss, restarts
  // from lower points, retried sensitivity solves, data that no stage uses.
  std::vector<std::string> warnings;
  std::string brief() const;        // one line
  std::string full_report() const;  // tables: stages, estimates, correlation, flags, profiles
};

// The units, names and validity of observables: the SI unit of a state or reported output of `fs`; throws
// ConfigError naming the valid names.
std::string observable_unit(const Flowsheet& fs, const std::string& name);

// What experiments promise before any simulation: sizes, sigmas, increasing finite sample times within t_end,
// unique names, settings that name constant parameters of `fs` (not inputs, not link targets) within their
// bounds, observations that name a state or reported output. Throws ConfigError naming the experiment, the key
// and the value. calibrate() calls it.
// `measured`: the observations' values are data to fit, so a size or absolute temperature must be positive and a mass
// not negative (false for predictions, whose values are placeholders).
void check_experiments(const Flowsheet& fs, const std::vector<Experiment>& experiments, bool measured = true);

// Runs the stages in order on clones of `scene`; each starts from the estimates of the previous one and the
// first from the scene's current parameter values (override them with `start`). `registry` builds the clones.
CalibrationResult calibrate(const Scene& scene, const Registry<Unit>& registry,
                            const std::vector<Experiment>& experiments, const std::vector<Stage>& stages,
                            const CalibrationOptions& options, const std::map<std::string, double>& start = {});

// Model predictions at the sampled times, for the scene's parameters overridden by `params`.
struct Prediction {
  std::string experiment, observable;
  std::vector<double> t, data, model, sigma;  // sigma: σ_abs, or σ_rel times the model (kModel) or data (kData)
};
std::vector<Prediction> predict(const Scene& scene, const Registry<Unit>& registry,
                                const std::vector<Experiment>& experiments, const std::map<std::string, double>& params,
                                const CalibrationOptions& options);

// R² = 1 - SS_res / SS_tot and RMSE per observable over all experiments and samples (NaN data skipped).
struct FitStatistics {
  std::string observable;
  long n = 0;
  double r2 = 0.0, rmse = 0.0, mean_abs_rel = 0.0;
};
std::vector<FitStatistics> fit_statistics(const std::vector<Prediction>& predictions);

// Observations that no stage uses (a stage without observables uses all): "name (experiments ...; n samples)".
std::vector<std::string> unused_observations(const std::vector<Experiment>& experiments,
                                             const std::vector<Stage>& stages);

namespace calibration_testing {
// A test seam: when set, called before every sensitivity solve with the experiment's name; returning true makes
// that solve fail as an integrator failure would (SolverError). Only tests set it.
extern std::function<bool(const std::string&)> fail_sensitivity_solve;
}  // namespace calibration_testing

// The residuals of one stage as a function of θ, for tests, Jacobian checks and custom solvers.
class StageProblem {
 public:
  StageProblem(const Scene& scene, const Registry<Unit>& registry, const std::vector<Experiment>& experiments,
               const Stage& stage, const CalibrationOptions& options, const std::map<std::string, double>& start = {});
  ~StageProblem();
  StageProblem(const StageProblem&) = delete;
  StageProblem& operator=(const StageProblem&) = delete;
  int num_parameters() const;
  int num_residuals() const;
  std::vector<double> theta0() const;  // the start in θ
  std::vector<double> to_theta(const std::vector<double>& p) const;
  std::vector<double> to_params(const std::vector<double>& theta) const;  // SI
  // Residuals at θ, and the row-major num_residuals x num_parameters Jacobian if `jacobian` != nullptr. With
  // SigmaBasis::kModel the weights are those of the last Jacobian evaluation (the first call sets them).
  // Throws SolverError if a simulation fails.
  void evaluate(const std::vector<double>& theta, std::vector<double>& residuals, std::vector<double>* jacobian);
  long simulations() const;
  long sensitivity_solves() const;

  struct Impl;

 private:
  Impl* impl_;
};

}  // namespace granuflow
