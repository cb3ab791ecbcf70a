// The block-diagonal preconditioner of the iterative linear solver (DaeSystem::precondition_setup/solve): one block per
// unit with states. A unit that declares a preconditioner (UnitSpec::set_preconditioner) builds and applies its own;
// every other unit's block is its exact own block of dF/dx + cj dF/dx' (the columns of its own states), assembled
// the way DaeSystem::jacobian assembles it (analytic part, coloured forward AD) and LU-factored. Blocks larger than
// kMaxDenseBlock keep their diagonal only. Inlined explicit units are no unknowns and have no block; the others read
// their states, evaluated at the setup.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "granuflow/dae_system.hpp"

namespace granuflow {

namespace {
constexpr int kMaxDenseBlock = 2000;

// Keeps the entries of one unit's rows on its own states' columns.
class OwnBlockSink : public JacobianSink {
 public:
  OwnBlockSink(Eigen::MatrixXd& m, int offset, bool diagonal_only) : m_(m), off_(offset), diag_(diagonal_only) {}

 protected:
  void add_entry(int row, int col, double v) override {
    const int c = col - off_;
    if (c < 0 || c >= (diag_ ? static_cast<int>(m_.rows()) : static_cast<int>(m_.cols()))) return;
    if (diag_) {
      if (c == row) m_(row, 0) += v;
      return;
    }
    m_(row, c) += v;
  }

 private:
  Eigen::MatrixXd& m_;
  int off_;
  bool diag_;
};
}  // namespace

struct DaeSystem::BlockPreconditioner {
  struct Block {
    bool own = false;  // the unit preconditions itself
    bool diagonal = false;
    Eigen::MatrixXd m;  // the block, or its diagonal (one column)
    Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  };
  std::vector<Block> blocks;  // per unit
  std::vector<double> y, yp;  // every state at the setup (explicit ones evaluated when inlined)
};

void DaeSystem::precondition_setup(double t, const double* y_in, const double* yp_in, double cj) {
  const auto& units = fs_.units();
  if (!prec_) prec_ = std::make_shared<BlockPreconditioner>();
  prec_->blocks.resize(units.size());
  prec_->y.resize(n_ext_), prec_->yp.resize(n_ext_);
  extend(t, y_in, yp_in, prec_->y.data(), prec_->yp.data());
  const double* y = prec_->y.data();
  const double* yp = prec_->yp.data();
  fill_params(t);
  bool jets = false;
  for (size_t u = 0; u < units.size(); ++u) {
    const UnitInstance& inst = units[u];
    const int ns = static_cast<int>(inst.spec.states().size());
    auto& b = prec_->blocks[u];
    if (ns == 0 || (inline_ && inst.spec.is_explicit())) continue;
    Ctx<double> c{t, y, yp, pvals_[u].data(), rbuf_.data(), inst.offset, &inst.port_index, segment_start_};
    c.work = ws_[u].get();
    if (inst.shared >= 0) c.shared = pvals_[inst.shared].data();
    if (inst.spec.has_preconditioner()) {
      b.own = true;
      inst.unit->precondition_setup(c, cj);
      continue;
    }
    if (!jets) {        // the AD sweeps read every state as a Jet
      jets_plain_ = 0;  // its sweeps seed their own directions
      for (int i = 0; i < n_ext_; ++i) xj_[i] = Jet(y[i]), xdj_[i] = Jet(yp[i]);
      params_as_jets();
      jets = true;
    }
    b.diagonal = ns > kMaxDenseBlock;
    b.m.setZero(ns, b.diagonal ? 1 : ns);
    OwnBlockSink sink(b.m, inst.offset, b.diagonal);
    if (inst.spec.has_analytic_part()) inst.unit->analytic_jacobian(c, cj, sink);
    if (!inst.spec.analytic_complete()) ad_unit(static_cast<int>(u), t, y, yp, cj, sink);
    if (b.diagonal) {
      for (int k = 0; k < ns; ++k)
        if (b.m(k, 0) == 0.0) b.m(k, 0) = 1.0;  // a row without a diagonal entry is left alone
    } else {
      b.lu.compute(b.m);
    }
  }
}

void DaeSystem::precondition_solve(double t, const double*, const double*, double cj, const double* r, double* z) {
  const auto& units = fs_.units();
  const double* y = prec_->y.data();  // the state of the setup; a unit's own solve reads what it kept there
  const double* yp = prec_->yp.data();
  for (size_t u = 0; u < units.size(); ++u) {
    const UnitInstance& inst = units[u];
    const int ns = static_cast<int>(inst.spec.states().size()), off = inst.offset;
    if (ns == 0 || (inline_ && inst.spec.is_explicit())) continue;
    const auto& b = prec_->blocks[u];
    if (b.own) {
      Ctx<double> c{t, y, yp, pvals_[u].data(), rbuf_.data(), off, &inst.port_index, segment_start_};
      c.work = ws_[u].get();
      if (inst.shared >= 0) c.shared = pvals_[inst.shared].data();
      inst.unit->precondition_solve(c, cj, r + off, z + off);
    } else if (b.diagonal) {
      for (int k = 0; k < ns; ++k) z[off + k] = r[off + k] / b.m(k, 0);
    } else {
      Eigen::Map<Eigen::VectorXd>(z + off, ns) = b.lu.solve(Eigen::Map<const Eigen::VectorXd>(r + off, ns));
    }
  }
}

}  // namespace granuflow
