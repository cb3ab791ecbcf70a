// Consistent initial values by Newton on the algebraic states (framework/src/consistent_start.hpp): the point it
// returns satisfies every residual, it steps back from states the units refuse, it gives way to IDACalcIC when a unit
// breaks the residual contract, and the runs that start from it give the known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "consistent_start.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

// dm/dt = -k m with an algebraic a tied to m: the cubic a^3 + a = m (monotone, one root), the logarithmic
// ln a = ln(m / 2) (refuses a <= 0, where its Newton from a far guess first lands), or a = tau dm/dt, which reads y'
// and so breaks the contract.
enum class Tie { kCubic, kLog, kReadsRate };

class Decay : public UnitBase<Decay> {
 public:
  explicit Decay(Tie tie) : tie_(tie) {}
  std::string type() const override { return "decay"; }
  void declare(UnitSpec& s, Settings&) override {
    p_k_ = s.add_param({"k", "1/s", 0.5, 0.0, 10.0, "decay rate", "test"});
    s_m_ = s.add_state("m", StateKind::Differential, "kg", 1.0);
    s_a_ = s.add_state("a", StateKind::Algebraic, "kg", 1.0);
    o_a_ = s.add_output("a", "kg");
  }
  template <class T>
  Status eval(const Ctx<T>& c) const {
    const T& m = c.x(s_m_);
    const T& a = c.x(s_a_);
    c.res(s_m_) = c.xd(s_m_) + c.par(p_k_) * m;
    if (tie_ == Tie::kCubic) {
      c.res(s_a_) = a * a * a + a - m;
    } else if (tie_ == Tie::kLog) {
      if (!(a > 0.0)) return Status::kRecoverable;
      c.res(s_a_) = log(a) - log(0.5 * m);
    } else {
      c.res(s_a_) = a - 2.0 * c.xd(s_m_);
    }
    return Status::kOk;
  }
  template <class T>
  void init(InitCtx<T>& c) const {
    c.x(s_m_) = T(1.0);
    c.x(s_a_) = T(10.0);  // far from every root
  }
  template <class T>
  void outputs(const Ctx<T>& c) const {
    c.out(o_a_) = c.x(s_a_);
  }

 private:
  Tie tie_;
  ParamId p_k_;
  StateId s_m_, s_a_;
  OutputId o_a_;
};

std::unique_ptr<Flowsheet> decay(Tie tie) {
  auto fs = std::make_unique<Flowsheet>("decay");
  fs->add_unit("u", std::make_unique<Decay>(tie), Settings("u", {}));
  fs->finalize();
  return fs;
}

struct Start {
  std::vector<double> y0, y, yp, ewt;
  int block = 0;
};

Start start(DaeSystem& sys, detail::JacobianCache& cache) {
  Start s;
  sys.initial_values(s.y0);
  const int n = sys.size();
  s.y = s.y0, s.yp.assign(n, 0.0), s.ewt.resize(n);
  const auto scales = sys.scales();
  for (int i = 0; i < n; ++i) s.ewt[i] = 1.0 / (1e-6 * std::abs(s.y[i]) + 1e-8 * scales[i]);
  s.block = detail::consistent_start(sys, cache, 0.0, s.ewt.data(), s.y.data(), s.yp.data());
  return s;
}

TEST(ConsistentStart, SolvesANonlinearAlgebraicStateAndTheRatesExactly) {
  for (Tie tie : {Tie::kCubic, Tie::kLog}) {
    const auto fs = decay(tie);
    DaeSystem sys(*fs);
    detail::JacobianCache cache;
    const Start s = start(sys, cache);
    ASSERT_EQ(s.block, 2);
    EXPECT_EQ(cache.reusable, 1);
    EXPECT_FALSE(cache.valid);  // the first Newton matrix of the integrator is evaluated afresh
    EXPECT_EQ(s.y[0], 1.0);     // differential states are given
    // a^3 + a = 1 has the root 0.6823278038280193, ln a = ln(1/2) the root 1/2: found to a thousandth of the
    // integrator's local tolerance (rtol 1e-6, atol 1e-8 here), where IDACalcIC stops at a third of a hundredth
    const double root = tie == Tie::kCubic ? 0.6823278038280193 : 0.5;
    EXPECT_NEAR(s.y[1], root, 1e-3 * (1e-6 * root + 1e-8));
    EXPECT_NEAR(s.yp[0], -0.5, 1e-15);  // dm/dt = -k m
  }
}

TEST(ConsistentStart, GivesWayToIdaCalcIcWhenAnAlgebraicResidualReadsARate) {
  const auto fs = decay(Tie::kReadsRate);
  DaeSystem sys(*fs);
  detail::JacobianCache cache;
  const Start s = start(sys, cache);
  EXPECT_EQ(s.block, 0);
  EXPECT_EQ(cache.reusable, 0);
  EXPECT_EQ(s.y, s.y0);  // untouched
  // the run itself starts through IDACalcIC and keeps a = 2 dm/dt = -k m exactly along the way
  SimOptions o;
  o.t_end = 2.0, o.t_out = {0.0, 1.0, 2.0};
  const SimResult r = simulate(*fs, o);
  for (size_t k = 0; k < r.t.size(); ++k) {
    EXPECT_NEAR(r.state(k, 0), std::exp(-0.5 * r.t[k]), 1e-5) << r.t[k];
    EXPECT_NEAR(r.state(k, 1), -std::exp(-0.5 * r.t[k]), 1e-5) << r.t[k];
  }
}

TEST(ConsistentStart, RunsFromItFollowTheRootAlongTheDecay) {
  for (Tie tie : {Tie::kCubic, Tie::kLog}) {
    const auto fs = decay(tie);
    SimOptions o;
    o.t_end = 4.0, o.t_out = {0.0, 2.0, 4.0};
    const SimResult r = simulate(*fs, o);
    for (size_t k = 0; k < r.t.size(); ++k) {
      const double m = std::exp(-0.5 * r.t[k]);
      const double a = r.state(k, 1);
      EXPECT_NEAR(r.state(k, 0), m, 1e-5 * m) << r.t[k];
      EXPECT_NEAR(tie == Tie::kCubic ? a * a * a + a : 2.0 * a, m, 1e-5 * m) << r.t[k];
    }
    EXPECT_LT(r.stats.residuals, 200);
  }
}

TEST(ConsistentStart, HeadlineSceneStartsOnEveryResidual) {
  Scene scene = testing::scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  DaeSystem sys(*scene.flowsheet);
  const int n = sys.size();
  detail::JacobianCache cache;
  std::vector<double> r0(n), r(n);
  std::vector<double> y0;
  sys.initial_values(y0);
  std::vector<double> yp0(n, 0.0);
  ASSERT_EQ(sys.residual(0.0, y0.data(), yp0.data(), r0.data()), Status::kOk);
  const Start s = start(sys, cache);
  ASSERT_GT(s.block, 0);
  ASSERT_EQ(sys.residual(0.0, s.y.data(), s.yp.data(), r.data()), Status::kOk);
  const auto id = sys.differential_id();
  int moved = 0;
  for (int i = 0; i < n; ++i) {
    if (id[i] != 0.0) {
      EXPECT_EQ(s.y[i], y0[i]) << sys.describe_row(i);                                       // given
      EXPECT_LE(std::abs(r[i]), 1e-13 * std::abs(s.yp[i]) + 1e-300) << sys.describe_row(i);  // y' = f(y)
    } else {
      moved += s.y[i] != y0[i];
      // every algebraic equation solved to far below what its guess left
      EXPECT_LE(std::abs(r[i]), 1e-8 * std::abs(r0[i]) + 1e-14) << sys.describe_row(i);
    }
  }
  EXPECT_GT(moved, 0);  // the units' guesses are not consistent: there was something to solve
}

// IDACalcIC's horizon is 1 % of the first segment, so it grows with t_end: the sieve-mill loop with its decks swapped
// (the product deck to the mill, the oversize out) started from 30 h but failed at t = 0 from 59 h on, its Newton
// at a horizon of 35 min not converging. A start that fails is tried again over shorter horizons.
TEST(ConsistentStart, ALongFirstSegmentStillStarts) {
  std::string text = testing::scene_from_file("flowsheets/continuous_layering_sieve_mill.yaml").text;
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"sieve.oversize -> mill.in", "sieve.X -> mill.in"},
                                 {"sieve.product -> product.in", "sieve.oversize -> product.in"},
                                 {"sieve.X -> mill.in", "sieve.product -> mill.in"}}) {
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  Scene s = testing::scene_from_text(text);
  s.options.t_end = 59 * 3600.0;
  s.options.n_out = 3;
  const SimResult r = simulate(*s.flowsheet, s.options);
  EXPECT_EQ(r.t.back(), 59 * 3600.0);
  EXPECT_GT(r.stats.calcic_starts, 1);  // the first horizon failed: the retry is what started it
  EXPECT_GT(testing::output(r, r.t.size() - 1, "product.mdot"), 0.0);
}

}  // namespace
}  // namespace granuflow
