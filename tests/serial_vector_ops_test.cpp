// The compiled serial N_Vector kernels (framework/solver/serial_vector_ops)
// compute what SUNDIALS documents for each operation: every replaced
// operation on random vectors of several lengths, including the aliased
// calls IDA makes (z the same vector as x or y, the linear combination's
// result one of its terms), against SUNDIALS' own serial implementation and
// against the operation's formula.
#include <gtest/gtest.h>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <random>
#include <vector>

#include "framework/solver/serial_vector_ops.hpp"

namespace pneumo {
namespace {

struct Context {
  SUNContext ctx = nullptr;
  Context() { SUNContext_Create(nullptr, &ctx); }
  ~Context() { SUNContext_Free(&ctx); }
};

class SerialVectorOps : public ::testing::TestWithParam<int> {
 protected:
  // `n` random vectors with SUNDIALS' operations and their copies with the
  // compiled ones.
  void SetUp() override {
    const int len = GetParam();
    std::mt19937 rng(4242 + len);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int k = 0; k < 5; ++k) {
      plain.push_back(N_VNew_Serial(len, context.ctx));
      fast.push_back(N_VNew_Serial(len, context.ctx));
      use_compiled_serial_ops(fast.back());
      N_VEnableFusedOps_Serial(plain.back(), SUNTRUE);
      for (int i = 0; i < len; ++i) {
        const double v = u(rng) + (k == 1 ? 3.0 : 0.0);  // vector 1 without zeros (divisions)
        NV_Ith_S(plain.back(), i) = v;
        NV_Ith_S(fast.back(), i) = v;
      }
    }
    // A mask: positive, zero and negative entries.
    for (int i = 0; i < len; ++i) {
      const double m = i % 3 == 0 ? 1.0 : (i % 3 == 1 ? 0.0 : -1.0);
      NV_Ith_S(plain[4], i) = m;
      NV_Ith_S(fast[4], i) = m;
    }
  }
  void TearDown() override {
    for (auto* v : plain) N_VDestroy(v);
    for (auto* v : fast) N_VDestroy(v);
  }
  void expect_same(int k, const char* what) {
    for (sunindextype i = 0; i < NV_LENGTH_S(plain[k]); ++i)
      EXPECT_NEAR(NV_Ith_S(fast[k], i), NV_Ith_S(plain[k], i), 1e-14 * (1.0 + std::abs(NV_Ith_S(plain[k], i))))
          << what << " entry " << i;
  }
  Context context;
  std::vector<N_Vector> plain, fast;
};

TEST_P(SerialVectorOps, ElementwiseOperationsMatchSundials) {
  const int len = GetParam();
  // z = a x + b y, also with z aliasing x.
  N_VLinearSum(0.7, plain[0], -1.3, plain[1], plain[2]);
  N_VLinearSum(0.7, fast[0], -1.3, fast[1], fast[2]);
  expect_same(2, "linear sum");
  for (int i = 0; i < len; ++i) EXPECT_DOUBLE_EQ(NV_Ith_S(fast[2], i), 0.7 * NV_Ith_S(fast[0], i) - 1.3 * NV_Ith_S(fast[1], i));
  N_VLinearSum(2.0, plain[0], 1.0, plain[1], plain[0]);
  N_VLinearSum(2.0, fast[0], 1.0, fast[1], fast[0]);
  expect_same(0, "linear sum into x");
  N_VProd(plain[0], plain[1], plain[2]);
  N_VProd(fast[0], fast[1], fast[2]);
  expect_same(2, "product");
  N_VDiv(plain[0], plain[1], plain[2]);
  N_VDiv(fast[0], fast[1], fast[2]);
  expect_same(2, "quotient");
  N_VScale(-0.25, plain[2], plain[3]);
  N_VScale(-0.25, fast[2], fast[3]);
  expect_same(3, "scale");
  N_VAbs(plain[3], plain[3]);
  N_VAbs(fast[3], fast[3]);
  expect_same(3, "abs");
  N_VInv(plain[1], plain[2]);
  N_VInv(fast[1], fast[2]);
  expect_same(2, "inverse");
  N_VAddConst(plain[2], 5.5, plain[2]);
  N_VAddConst(fast[2], 5.5, fast[2]);
  expect_same(2, "add constant");
  N_VConst(3.25, plain[3]);
  N_VConst(3.25, fast[3]);
  expect_same(3, "constant");
}

TEST_P(SerialVectorOps, NormsMatchSundialsAndTheirFormulas) {
  const int len = GetParam();
  EXPECT_NEAR(N_VWrmsNorm(fast[0], fast[1]), N_VWrmsNorm(plain[0], plain[1]), 1e-14);
  EXPECT_NEAR(N_VWrmsNormMask(fast[0], fast[1], fast[4]), N_VWrmsNormMask(plain[0], plain[1], plain[4]), 1e-14);
  EXPECT_DOUBLE_EQ(N_VMaxNorm(fast[0]), N_VMaxNorm(plain[0]));
  double sum = 0.0, masked = 0.0, max_abs = 0.0;
  for (int i = 0; i < len; ++i) {
    const double p = NV_Ith_S(fast[0], i) * NV_Ith_S(fast[1], i);
    sum += p * p;
    if (NV_Ith_S(fast[4], i) > 0) masked += p * p;
    max_abs = std::max(max_abs, std::abs(NV_Ith_S(fast[0], i)));
  }
  EXPECT_NEAR(N_VWrmsNorm(fast[0], fast[1]), std::sqrt(sum / len), 1e-14);
  EXPECT_NEAR(N_VWrmsNormMask(fast[0], fast[1], fast[4]), std::sqrt(masked / len), 1e-14);
  EXPECT_EQ(N_VMaxNorm(fast[0]), max_abs);
  realtype nf[2], np[2];
  N_Vector xf[2] = {fast[0], fast[2]}, wf[2] = {fast[1], fast[1]};
  N_Vector xp[2] = {plain[0], plain[2]}, wp[2] = {plain[1], plain[1]};
  N_VWrmsNormVectorArray(2, xf, wf, nf);
  N_VWrmsNormVectorArray(2, xp, wp, np);
  EXPECT_NEAR(nf[0], np[0], 1e-14);
  EXPECT_NEAR(nf[1], np[1], 1e-14);
  N_VWrmsNormMaskVectorArray(2, xf, wf, fast[4], nf);
  N_VWrmsNormMaskVectorArray(2, xp, wp, plain[4], np);
  EXPECT_NEAR(nf[0], np[0], 1e-14);
  EXPECT_NEAR(nf[1], np[1], 1e-14);
}

TEST_P(SerialVectorOps, FusedOperationsMatchSundials) {
  realtype c[4] = {0.5, -2.0, 1.25, 3.0};
  // z = sum c_j X_j, the result one of the terms (IDA's predictor does so).
  N_Vector Xp[4] = {plain[2], plain[0], plain[1], plain[3]}, Xf[4] = {fast[2], fast[0], fast[1], fast[3]};
  for (int nvec : {1, 2, 3, 4}) {
    N_VLinearCombination(nvec, c, Xp, plain[2]);
    N_VLinearCombination(nvec, c, Xf, fast[2]);
    expect_same(2, "linear combination");
  }
  // Z_j = a_j x + Y_j; Z_j = c_j X_j; Z_j = a X_j + b Y_j; Z_j = c.
  N_Vector Yp[2] = {plain[1], plain[3]}, Yf[2] = {fast[1], fast[3]};
  N_Vector Zp[2] = {plain[2], plain[3]}, Zf[2] = {fast[2], fast[3]};
  N_VScaleAddMulti(2, c, plain[0], Yp, Zp);
  N_VScaleAddMulti(2, c, fast[0], Yf, Zf);
  expect_same(2, "scale add multi");
  expect_same(3, "scale add multi (in place)");
  N_VScaleVectorArray(2, c, Yp, Zp);
  N_VScaleVectorArray(2, c, Yf, Zf);
  expect_same(2, "scale vector array");
  expect_same(3, "scale vector array (in place)");
  N_Vector Xp2[2] = {plain[0], plain[1]}, Xf2[2] = {fast[0], fast[1]};
  N_VLinearSumVectorArray(2, 1.5, Xp2, -0.5, Yp, Zp);
  N_VLinearSumVectorArray(2, 1.5, Xf2, -0.5, Yf, Zf);
  expect_same(2, "linear sum vector array");
  expect_same(3, "linear sum vector array");
  N_VConstVectorArray(2, -7.0, Zp);
  N_VConstVectorArray(2, -7.0, Zf);
  expect_same(2, "constant vector array");
  expect_same(3, "constant vector array");
}

// A clone (IDA's own vectors) keeps the compiled kernels.
TEST_P(SerialVectorOps, ClonesInheritTheKernels) {
  N_Vector c = N_VClone(fast[0]);
  EXPECT_EQ(c->ops->nvwrmsnorm, fast[0]->ops->nvwrmsnorm);
  EXPECT_EQ(c->ops->nvlinearcombination, fast[0]->ops->nvlinearcombination);
  EXPECT_NE(c->ops->nvwrmsnorm, plain[0]->ops->nvwrmsnorm);
  N_VDestroy(c);
}

INSTANTIATE_TEST_SUITE_P(Lengths, SerialVectorOps, ::testing::Values(1, 3, 10, 51));

}  // namespace
}  // namespace pneumo
