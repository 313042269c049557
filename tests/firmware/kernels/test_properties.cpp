// Properties of the kernels together on random non-singular states (props_fixture.hpp): the float
// kernels against double; and the float elementary functions (osc/math/scalar.hpp) against double over
// their stated ranges. Each kernel's own properties are in the file of its header: test_dynamics.cpp,
// test_kinematics.cpp, test_opspace.cpp, test_friction.cpp.
#include <gtest/gtest.h>

#include <bit>

#include <cmath>
#include <cstdio>
#include <limits>

#include "osc/control/params.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/control/arm_opspace.hpp"
#include "props_fixture.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST_F(Props, FloatKernelsAgreeWithDouble) {
  // Tolerance, relative (Frobenius / Euclidean): 1e-4 for A, J, Ja, g, c, tau_f, Lambda; 2e-4 for
  // Psi. Justification: float round-off is u = 6e-8. A, J, g, c come from short recursions (~6
  // levels of 3x3 products and cross products, sums of same-size terms): a few hundred u at most,
  // ~3e-5, before counting the rounding of q itself (u |q| |dF/dq| / |F| ~ a few u). Lambda =
  // J^-T A J^-1 and Psi (two solves with Ja and a difference of h(y+z), h(y-z)) multiply that by
  // the condition number of the 3x3 blocks, which q_nonsingular bounds (|sin q5|, |cos(q3+0.047)|
  // >= 0.2): observed worst (printed) is 10-100x below these bounds.
  const Model<float> mf = Model<float>::of(robot::kArm);
  Data<float> df;
  ArmOpSpace<float> of;
  FrictionParams<double> pd;
  for (int i = 0; i < kDof; ++i) {
    pd.vis(i) = robot::kFrictionPaper.vis[i];
    pd.cou(i) = robot::kFrictionPaper.cou[i];
    pd.sti(i) = robot::kFrictionPaper.sti[i];
    pd.dec(i) = params::kTauDec;
  }
  const FrictionParams<float> pf{pd.vis.cast<float>(), pd.cou.cast<float>(), pd.sti.cast<float>(),
                                 pd.dec.cast<float>()};
  auto rel = [](const auto& f, const auto& d) {
    return (f.template cast<double>() - d).norm() / std::max(d.norm(), 1e-6);
  };
  double wA = 0, wL = 0, wc = 0, wg = 0, wJ = 0, wJa = 0, wP = 0, wF = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0), v = rs.vec(0.2);
    const Mat3<double> R_ref = reference_for(k, q);
    const Vec6<float> qf = q.cast<float>(), qdf = qd.cast<float>(), vf = v.cast<float>();
    const Mat3<float> R_ref_f = R_ref.cast<float>();
    Vec6<double> c, h, tf;
    Vec6<float> cf, hf, tff;
    update(q, R_ref);
    {
      NoMalloc guard;
      c = velocity_products(model, data, qd).c;
      h = psi_quadratic(model, data, os, v);
      tf = friction_torque(pd, qd);
      opspace_update(mf, df, of, qf, R_ref_f);
      cf = velocity_products(mf, df, qdf).c;
      hf = psi_quadratic(mf, df, of, vf);
      tff = friction_torque(pf, qdf);
    }
    wA = std::max(wA, rel(df.A, data.A));
    wJ = std::max(wJ, rel(df.J, data.J));
    wJa = std::max(wJa, rel(of.Ja, os.Ja));
    wL = std::max(wL, rel(operational_inertia(df, of), operational_inertia(data, os)));
    wg = std::max(wg, rel(of.g, os.g));
    wc = std::max(wc, rel(cf, c));
    wP = std::max(wP, rel(hf, h));
    wF = std::max(wF, rel(tff, tf));
  }
  std::printf(
      "float vs double, max relative: A %.1e, J %.1e, Ja %.1e, Lambda %.1e, g %.1e, c %.1e, Psi %.1e, "
      "tau_f %.1e\n",
      wA, wJ, wJa, wL, wg, wc, wP, wF);
  EXPECT_LT(wA, 1e-4);
  EXPECT_LT(wJ, 1e-4);
  EXPECT_LT(wJa, 1e-4);
  EXPECT_LT(wL, 1e-4);
  EXPECT_LT(wg, 1e-4);
  EXPECT_LT(wc, 1e-4);
  EXPECT_LT(wF, 1e-4);
  EXPECT_LT(wP, 2e-4);
}

TEST(FloatFunctions, SinCosAndExpWithinTheirStatedErrors) {
  // math::sincos / sin / cos / exp for float (scalar.hpp, detail::sincos_float and exp_float)
  // against double at every argument of a dense grid over their stated ranges.
  double ws = 0, wc = 0, we = 0, ws_at = 0, we_at = 0;
  for (int i = -2000000; i <= 2000000; ++i) {
    const float v = static_cast<float>(i * 0.0032);  // |v| <= 6400
    float s, c;
    math::sincos(v, s, c);
    const double es = std::abs(s - std::sin(static_cast<double>(v)));
    const double ec = std::abs(c - std::cos(static_cast<double>(v)));
    if (es > ws) ws = es, ws_at = v;
    wc = std::max(wc, ec);
    EXPECT_EQ(math::sin(v), s);
    EXPECT_EQ(math::cos(v), c);
  }
  for (int i = -873000; i <= 885000; ++i) {
    const float v = static_cast<float>(i * 1e-4);  // e^v a normal float
    const double exact = std::exp(static_cast<double>(v));
    const double e = std::abs(math::exp(v) - exact) / exact;
    if (e > we) we = e, we_at = v;
  }
  std::printf(
      "float sin: worst |error| %.2e at %.4f, cos %.2e (stated 6e-8); exp: worst relative %.2e at %.4f "
      "(stated 2.4e-7)\n",
      ws, ws_at, wc, we, we_at);
  EXPECT_LE(ws, 6e-8);
  EXPECT_LE(wc, 6e-8);
  EXPECT_LE(we, 2.4e-7);
  EXPECT_EQ(math::exp(-100.0f), 0.0f);
  EXPECT_EQ(math::exp(100.0f), HUGE_VALF);
  EXPECT_TRUE(std::isnan(math::exp(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(math::exp(0.0f), 1.0f);
  // exp_decay (v <= 0, without exp's checks above 0) is exp, bit for bit, down to where e^v is 0; and at the
  // top of exp's range (v in [88.37, 88.5]), where 2^k takes two factors (k = 128), exp is finite and within its
  // error.
  int decay_differs = 0;
  for (int i = -900000; i <= 0; ++i) {
    const float v = static_cast<float>(i * 1e-4);
    if (std::bit_cast<std::uint32_t>(math::exp_decay(v)) != std::bit_cast<std::uint32_t>(math::exp(v))) ++decay_differs;
  }
  EXPECT_EQ(decay_differs, 0);
  EXPECT_TRUE(std::isnan(math::exp_decay(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(math::exp_decay(-100.0f), 0.0f);
  EXPECT_EQ(math::exp_decay(-0.0f), 1.0f);
  EXPECT_EQ(math::exp_decay(-1.0), std::exp(-1.0));
  for (const float v : {88.38f, 88.45f, 88.5f}) {
    const double exact = std::exp(static_cast<double>(v));
    EXPECT_LE(std::abs(math::exp(v) - exact) / exact, 2.4e-7) << v;
  }
}

TEST(FloatFunctions, Atan2AndAsinWithinTheirStatedErrors) {
  // math::atan2 / asin for float (scalar.hpp, detail::atan2_float) against double: every direction
  // of a dense fan in all four quadrants, at radii from 1e-30 to 1e30, and asin over [-1, 1].
  double wa = 0, wa_at = 0, ws = 0;
  for (int i = 0; i < 400000; ++i) {
    const double angle = -3.14159265358979 + i * (2 * 3.14159265358979 / 400000);
    const double radius = std::pow(10.0, (i % 61) - 30);
    const float y = static_cast<float>(radius * std::sin(angle)), x = static_cast<float>(radius * std::cos(angle));
    const double e = std::abs(math::atan2(y, x) - std::atan2(static_cast<double>(y), static_cast<double>(x)));
    if (e > wa) wa = e, wa_at = angle;
  }
  for (int i = -1000000; i <= 1000000; ++i) {
    const float v = static_cast<float>(i * 1e-6);
    ws = std::max(ws, std::abs(math::asin(v) - std::asin(static_cast<double>(v))));
  }
  std::printf("float atan2: worst |error| %.2e at angle %.4f; asin %.2e (stated 2.4e-7)\n", wa, wa_at, ws);
  EXPECT_LE(wa, 2.4e-7);
  EXPECT_LE(ws, 2.4e-7);
  // IEEE's signed zeros and the axes, exactly; NaN in, NaN out.
  const float pi = 3.14159265358979f, half_pi = 1.57079632679490f;
  EXPECT_EQ(math::atan2(0.0f, 1.0f), 0.0f);
  EXPECT_TRUE(std::signbit(math::atan2(-0.0f, 1.0f)));
  EXPECT_EQ(math::atan2(0.0f, -0.0f), pi);
  EXPECT_EQ(math::atan2(-0.0f, -1.0f), -pi);
  EXPECT_EQ(math::atan2(2.0f, 0.0f), half_pi);
  EXPECT_EQ(math::atan2(-2.0f, 0.0f), -half_pi);
  EXPECT_NEAR(math::atan2(1.0f, 1.0f), pi / 4, 6e-8);
  EXPECT_NEAR(math::atan2(-1.0f, -1.0f), -3 * pi / 4, 2.4e-7);
  EXPECT_EQ(math::asin(1.0f), half_pi);
  EXPECT_EQ(math::asin(-1.0f), -half_pi);
  EXPECT_TRUE(std::isnan(math::atan2(std::numeric_limits<float>::quiet_NaN(), 1.0f)));
  EXPECT_TRUE(std::isnan(math::asin(1.0001f)));
}

}  // namespace
