// IDAS as a stepper of the run driver: any DAE, with quadratures and forward sensitivities. A segment starts from
// consistent values: an exact Newton on the algebraic states where the units keep the residual contract
// (consistent_start.hpp), IDACalcIC otherwise, then consistent initial sensitivities from one linear solve
// (consistent_sensitivities.hpp).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "solver_setup.hpp"
#include "stepper.hpp"

namespace granuflow::detail {

class IdaStepper : public Stepper {
 public:
  // `kind`: the linear solver (dense inlines the explicit units); `j0`: the Jacobian at the initial state (cj = 0,
  // column-major), empty unless the system is inlined, for the first consistent start; `reason`: why IDAS runs.
  IdaStepper(DaeSystem& sys, const SimOptions& opt, LinearSolverKind kind, const std::vector<int>& sens_ids,
             std::vector<double> j0, std::string reason);
  ~IdaStepper() override;
  IdaStepper(const IdaStepper&) = delete;
  IdaStepper& operator=(const IdaStepper&) = delete;

  int begin_segment(size_t seg, double t0, double t1, SolverStats& stats) override;
  int advance(double tout, double& t) override;
  bool segment_done(int flag, double, double) const override { return flag == IDA_TSTOP_RETURN; }
  Sample sample(double t) override;
  void end_segment(double t0, double t1) override;
  StepFailure failure(int flag) override;
  void finish(SolverStats& stats) override;
  void set_roots(int n, RootFunction g, const std::vector<int>& directions) override;
  bool root_found(int flag) const override { return flag == IDA_ROOT_RETURN; }
  std::vector<int> roots() override;
  void jump_sensitivities(SensitivityJump jump) override { jump_ = std::move(jump), jump_pending_ = true; }
  bool save(StepperState& s) override;
  void restore(const StepperState& s) override;

 private:
  void apply_jump(double t);
  void add_current_counts(SolverStats& s) const;  // IDAReInit zeroes IDAS's counters: added up before each restart
  void init_quadratures();
  void init_sensitivities();
  // After a consistent start with sensitivities off: their consistent initial values, and IDAS re-initialized.
  void sensitivity_initial_conditions(double t);
  int start_consistently(size_t seg, double t0, double t1, SolverStats& stats);

  DaeSystem& sys_;
  const SimOptions& opt_;
  LinearSolverKind kind_;
  bool dense_;
  std::vector<int> sens_ids_;
  std::vector<double> j0_, ewt_;
  std::string reason_, failed_call_;
  int n_, nq_, ns_;
  Context C_;
  NVec y_, yp_, atol_, q_, qatol_;
  IdaUser user_;
  std::unique_ptr<Ida> ida_;
  std::unique_ptr<NVec> constraints_;  // non-negative inventories (DaeSystem::constraints), if any
  N_Vector* yS_ = nullptr;
  N_Vector* ypS_ = nullptr;
  N_Vector* qS_ = nullptr;
  std::vector<const double*> yS_now_, qS_now_;
  SolverStats counts_;
  int n_roots_ = 0;
  SensitivityJump jump_;
  bool jump_pending_ = false;
  bool restored_ = false;  // the next segment starts from restore()d values, not from IDAS's last step
};

}  // namespace granuflow::detail
