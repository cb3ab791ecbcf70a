// The optimized serial vector operations (framework/src/serial_vector_ops.hpp) against SUNDIALS' own, operation by
// operation on the same data: every result bit for bit, aliased arguments included, so that installing them changes
// the integrators' speed and nothing else.
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <functional>
#include <random>
#include <vector>

#include "serial_vector_ops.hpp"

namespace granuflow {
namespace {

constexpr int kN = 37;  // not a multiple of any vector width

struct Pair {
  SUNContext ctx = nullptr;
  std::vector<N_Vector> lib, ours;  // the same values, SUNDIALS' operations / ours
  explicit Pair(int count) {
    SUNContext_Create(nullptr, &ctx);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    N_Vector a = N_VNew_Serial(kN, ctx), b = N_VNew_Serial(kN, ctx);
    N_VEnableFusedOps_Serial(a, SUNTRUE);
    detail::install_serial_vector_ops(b);
    for (int k = 0; k < count; ++k) {
      lib.push_back(N_VClone(a));
      ours.push_back(N_VClone(b));
      for (int i = 0; i < kN; ++i) {
        // zeros (inverse tests, quotients, masks) and small integers (constraint codes) among the values
        const double v = i % 9 == 4 ? 0.0 : k == count - 1 ? double(int(u(rng) * 1.3)) : u(rng);
        NV_Ith_S(lib[k], i) = NV_Ith_S(ours[k], i) = v;
      }
    }
    N_VDestroy(a), N_VDestroy(b);
  }
  ~Pair() {
    for (auto* v : lib) N_VDestroy(v);
    for (auto* v : ours) N_VDestroy(v);
    SUNContext_Free(&ctx);
  }
  void expect_equal(const char* what) const {
    for (size_t k = 0; k < lib.size(); ++k)
      for (int i = 0; i < kN; ++i) {
        const double a = NV_Ith_S(lib[k], i), b = NV_Ith_S(ours[k], i);
        if (std::isnan(a))
          EXPECT_TRUE(std::isnan(b)) << what << ": vector " << k << ", element " << i;
        else
          EXPECT_EQ(a, b) << what << ": vector " << k << ", element " << i;
      }
  }
};

// Runs `op` on both sets and compares every vector afterwards (and the returned value).
void same(const char* what, const std::function<double(std::vector<N_Vector>&)>& op) {
  Pair p(6);
  const double a = op(p.lib), b = op(p.ours);
  EXPECT_EQ(a, b) << what;
  p.expect_equal(what);
}

TEST(SerialVectorOps, InstalledIntoTheVectorAndItsClones) {
  Pair p(1);
  EXPECT_NE(p.lib[0]->ops->nvlinearsum, p.ours[0]->ops->nvlinearsum);
  EXPECT_NE(p.lib[0]->ops->nvlinearcombination, p.ours[0]->ops->nvlinearcombination);
  N_Vector c = N_VClone(p.ours[0]);
  EXPECT_EQ(c->ops->nvwrmsnorm, p.ours[0]->ops->nvwrmsnorm);
  N_VDestroy(c);
}

TEST(SerialVectorOps, ElementwiseOperationsEqualTheLibrarysBitForBit) {
  same("linear sum", [](auto& v) { return N_VLinearSum(0.3, v[0], -1.7, v[1], v[2]), 0.0; });
  same("linear sum into x", [](auto& v) { return N_VLinearSum(1.0, v[0], -1.0, v[1], v[0]), 0.0; });
  same("linear sum into y", [](auto& v) { return N_VLinearSum(2.5, v[0], 1.0, v[1], v[1]), 0.0; });
  same("const", [](auto& v) { return N_VConst(0.25, v[3]), 0.0; });
  same("prod", [](auto& v) { return N_VProd(v[0], v[1], v[2]), 0.0; });
  same("div", [](auto& v) { return N_VDiv(v[0], v[1], v[2]), 0.0; });
  same("scale", [](auto& v) { return N_VScale(-3.0, v[0], v[2]), 0.0; });
  same("scale in place", [](auto& v) { return N_VScale(0.1, v[0], v[0]), 0.0; });
  same("abs", [](auto& v) { return N_VAbs(v[0], v[2]), 0.0; });
  same("inv", [](auto& v) { return N_VInv(v[1], v[2]), 0.0; });
  same("add const", [](auto& v) { return N_VAddConst(v[0], 1.5, v[2]), 0.0; });
  same("compare", [](auto& v) { return N_VCompare(0.7, v[0], v[2]), 0.0; });
  same("inv test", [](auto& v) { return double(N_VInvTest(v[0], v[2])); });
  same("inv test, no zero", [](auto& v) { return N_VAddConst(v[0], 5.0, v[1]), double(N_VInvTest(v[1], v[2])); });
  same("constraint mask", [](auto& v) { return double(N_VConstrMask(v[5], v[0], v[2])); });
  same("constraint mask, met", [](auto& v) {
    N_VAbs(v[0], v[1]);
    N_VAbs(v[5], v[3]);
    return double(N_VConstrMask(v[3], v[1], v[2]));
  });
}

TEST(SerialVectorOps, ReductionsEqualTheLibrarysBitForBit) {
  same("dot", [](auto& v) { return N_VDotProd(v[0], v[1]); });
  same("max norm", [](auto& v) { return N_VMaxNorm(v[0]); });
  same("wrms norm", [](auto& v) { return N_VWrmsNorm(v[0], v[1]); });
  same("wrms norm mask", [](auto& v) { return N_VWrmsNormMask(v[0], v[1], v[5]); });
  same("min", [](auto& v) { return N_VMin(v[0]); });
  same("wl2 norm", [](auto& v) { return N_VWL2Norm(v[0], v[1]); });
  same("l1 norm", [](auto& v) { return N_VL1Norm(v[0]); });
  same("min quotient", [](auto& v) { return N_VMinQuotient(v[0], v[1]); });
  same("min quotient, no denominator", [](auto& v) { return N_VConst(0.0, v[1]), N_VMinQuotient(v[0], v[1]); });
  same("wsqr sum", [](auto& v) { return N_VWSqrSumLocal(v[0], v[1]); });
  same("wsqr sum mask", [](auto& v) { return N_VWSqrSumMaskLocal(v[0], v[1], v[5]); });
}

TEST(SerialVectorOps, FusedAndArrayOperationsEqualTheLibrarysBitForBit) {
  double c[5] = {0.5, -1.25, 2.0, 1.0, 3.5};
  for (int nvec : {1, 2, 3, 5}) {
    same("linear combination", [&](auto& v) { return N_VLinearCombination(nvec, c, v.data(), v[5]), 0.0; });
    same("linear combination into X0", [&](auto& v) { return N_VLinearCombination(nvec, c, v.data(), v[0]), 0.0; });
    same("scale add multi", [&](auto& v) {
      N_Vector Y[5] = {v[1], v[2], v[3], v[4], v[5]}, Z[5] = {v[2], v[3], v[4], v[5], v[1]};
      return N_VScaleAddMulti(nvec, c, v[0], Y, Z), 0.0;
    });
    same("dot prod multi", [&](auto& v) {
      double d[5] = {};
      N_VDotProdMulti(nvec, v[0], v.data() + 1, d);
      return d[0] + 10 * d[nvec - 1];
    });
    same("scale vector array", [&](auto& v) { return N_VScaleVectorArray(nvec, c, v.data(), v.data() + 1), 0.0; });
    same("const vector array", [&](auto& v) { return N_VConstVectorArray(nvec, 0.5, v.data()), 0.0; });
    same("wrms norm vector array", [&](auto& v) {
      double d[5] = {};
      N_VWrmsNormVectorArray(nvec, v.data(), v.data() + 1, d);
      return d[0] + 10 * d[nvec - 1];
    });
    same("wrms norm mask vector array", [&](auto& v) {
      double d[5] = {};
      N_VWrmsNormMaskVectorArray(nvec, v.data(), v.data() + 1, v[5], d);
      return d[0] + 10 * d[nvec - 1];
    });
  }
  // z = X_2 is outside SUNDIALS' contract (z may be X_0 only; the library's own result is then wrong): ours is the sum
  {
    Pair p(4);
    std::vector<double> want(kN);
    for (int i = 0; i < kN; ++i)
      want[i] = c[0] * NV_Ith_S(p.ours[0], i) + c[1] * NV_Ith_S(p.ours[1], i) + c[2] * NV_Ith_S(p.ours[2], i);
    N_VLinearCombination(3, c, p.ours.data(), p.ours[2]);
    for (int i = 0; i < kN; ++i) EXPECT_EQ(NV_Ith_S(p.ours[2], i), want[i]) << i;
  }
  same("linear sum vector array", [&](auto& v) {
    N_Vector X[2] = {v[0], v[1]}, Y[2] = {v[2], v[3]}, Z[2] = {v[4], v[0]};
    return N_VLinearSumVectorArray(2, 0.5, X, -2.0, Y, Z), 0.0;
  });
}

}  // namespace
}  // namespace granuflow
