// The robot model (osc/kernels/model.hpp): the DH twists as the structure forward_kinematics uses; the
// model of an arm description, its mass-inertia error on the masses and inertias only; and its products in
// fixed point rounded once, where rounding each term would lose the sum (values of a few LSB).
#include <gtest/gtest.h>

#include <cmath>

#include "osc/kernels/model.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"

using namespace osc;

namespace {

TEST(Model, TwistsAreTheDhAnglesStructure) {
  EXPECT_EQ(twist_of(0.0), Twist::kZero);
  EXPECT_EQ(twist_of(kPi / 2), Twist::kPlusHalfPi);
  EXPECT_EQ(twist_of(-kPi / 2), Twist::kMinusHalfPi);
  EXPECT_EQ(twist_of(0.3), Twist::kGeneral);
  EXPECT_EQ(twist_of(kPi / 2 + 1e-9), Twist::kGeneral);
  EXPECT_EQ(twist_of(kPi), Twist::kGeneral);
  // The model's cosine and sine of each link's twist: exact where the structure replaces the product.
  const Model<double> m = Model<double>::of(robot::kArm);
  for (int i = 0; i < kDof; ++i) {
    const Model<double>::Link& l = m.link[i];
    if (l.twist == Twist::kGeneral) {
      EXPECT_NEAR(l.cos_alpha * l.cos_alpha + l.sin_alpha * l.sin_alpha, 1.0, 1e-15) << i;
      continue;
    }
    const double c = l.twist == Twist::kZero ? 1 : 0, s = l.twist == Twist::kZero ? 0 : 1;
    EXPECT_EQ(l.cos_alpha, c) << i;
    EXPECT_EQ(std::abs(l.sin_alpha), s) << i;
    EXPECT_EQ(l.sin_alpha < 0, l.twist == Twist::kMinusHalfPi) << i;
  }
}

TEST(Model, AMassInertiaErrorScalesTheLinksMassesAndInertiasOnly) {
  const Model<double> m = Model<double>::of(robot::kArm), h = Model<double>::of(robot::kArm, 0.1);
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(h.link[i].mass, 1.1 * m.link[i].mass, 1e-12) << i;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(h.link[i].inertia(a), 1.1 * m.link[i].inertia(a), 1e-15) << i;
      EXPECT_EQ(h.link[i].com(a), m.link[i].com(a)) << i;  // where the mass is: unchanged
    }
    EXPECT_EQ(h.link[i].a, m.link[i].a) << i;
    EXPECT_EQ(h.link[i].d, m.link[i].d) << i;
    EXPECT_EQ(h.armature(i), m.armature(i)) << i;  // the motors' inertia: not the links'
    const double G = robot::kArm.links[i].gear_ratio;
    EXPECT_NEAR(m.armature(i), G * G * robot::kArm.links[i].motor_inertia, 1e-15) << i;
  }
  EXPECT_EQ(h.gravity, m.gravity);
}

// Terms of 0.4 LSB each: rounded one by one they vanish, their exact sum rounds to 1 LSB.
TEST(Model, FixedPointProductsAreRoundedOnce) {
  const Fixed lsb = Fixed::lsb(), f = Fixed(0.4), zero = Fixed(0);
  ASSERT_EQ((lsb * f).raw(), 0);  // each product alone
  const Vec3<Fixed> u(lsb, lsb, zero), v(f, f, zero), w(zero, zero, zero);
  EXPECT_EQ(dot_sum(u, v, w, w).raw(), 1);
  EXPECT_EQ(dot_sum(w, w, u, v).raw(), 1);
  // a x b, first component a_1 b_2 - a_2 b_1 = lsb 0.4 - lsb (-0.4).
  const Vec3<Fixed> a(zero, lsb, lsb), b(zero, -f, f);
  const Vec3<Fixed> c = cross(a, b);
  EXPECT_EQ(c(0).raw(), 1);
  EXPECT_EQ(c(1).raw(), 0);
  EXPECT_EQ(c(2).raw(), 0);
  // a u + b v.
  const Vec3<Fixed> s = combine(lsb, Vec3<Fixed>(f, zero, f), lsb, Vec3<Fixed>(f, zero, -f));
  EXPECT_EQ(s(0).raw(), 1);
  EXPECT_EQ(s(2).raw(), 0);
  // In double: the same forms against hand-computed values.
  const Vec3<double> ud(1, 2, 3), vd(4, 5, 6);
  EXPECT_EQ(cross(ud, vd), Vec3<double>(-3, 6, -3));
  EXPECT_EQ(dot_sum(ud, vd, vd, ud), 64.0);
}

}  // namespace
