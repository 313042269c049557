// The robot model (osc/kernels/model.hpp): the placements' forms that forward_kinematics uses; the
// model of an arm description, its mass-inertia error on the masses and inertias only; and its products in
// fixed point rounded once, where rounding each term would lose the sum (values of a few LSB).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string_view>

#include "osc/kernels/kinematics.hpp"
#include "osc/kernels/model.hpp"
#include "osc/math/fixed.hpp"
#include "osc/robot.hpp"

using namespace osc;

namespace {

TEST(Model, PlacementFormsAreTheStructureOfEachPlacement) {
  // The DH twists 0, +-pi/2 and pi are signed permutations; other angles are general rotations.
  EXPECT_EQ(placement_form(dh_placement(0.1, 0.2, 0)).rotation, Rotation::kIdentity);
  const PlacementForm plus = placement_form(dh_placement(0.1, 0.2, kPi / 2));
  EXPECT_EQ(plus.rotation, Rotation::kRxPlusHalfPi);
  EXPECT_EQ(plus.column[0], 1);   // x stays
  EXPECT_EQ(plus.column[1], 3);   // y' = z
  EXPECT_EQ(plus.column[2], -2);  // z' = -y
  EXPECT_TRUE(plus.planar);
  const PlacementForm minus = placement_form(dh_placement(0, 0, -kPi / 2));
  EXPECT_EQ(minus.rotation, Rotation::kRxMinusHalfPi);
  EXPECT_EQ(minus.column[1], -3);
  EXPECT_EQ(minus.column[2], 2);
  const PlacementForm half = placement_form(dh_placement(0, 0, kPi));
  EXPECT_EQ(half.rotation, Rotation::kPermutation);
  EXPECT_EQ(half.column[1], -2);
  EXPECT_EQ(half.column[2], -3);
  Placement tilted = dh_placement(0, 0, 0);
  tilted.R[1][1] = tilted.R[2][2] = std::cos(0.3);
  tilted.R[2][1] = std::sin(0.3), tilted.R[1][2] = -std::sin(0.3);
  tilted.p[1] = 0.05;
  const PlacementForm general = placement_form(tilted);
  EXPECT_EQ(general.rotation, Rotation::kGeneral);
  EXPECT_FALSE(general.planar);
  // The built arm's placements: the model's copy is the table's, and every PUMA link has the fast forms.
  const Model<double> m = Model<double>::of(robot::kArm);
  for (int i = 0; i < kDof; ++i) {
    const Placement& P = robot::kArm.links[i].placement;
    for (int r = 0; r < 3; ++r) {
      EXPECT_EQ(m.link[i].p(r), P.p[r]) << i;
      for (int c = 0; c < 3; ++c) EXPECT_EQ(m.link[i].R(r, c), P.R[r][c]) << i;
    }
    if (std::string_view(robot::kArm.name) == "PUMA 560") {
      EXPECT_NE(m.link[i].form.rotation, Rotation::kPermutation) << i;  // the DH forms
      EXPECT_NE(m.link[i].form.rotation, Rotation::kGeneral) << i;
      EXPECT_TRUE(m.link[i].form.planar) << i;
      EXPECT_TRUE(m.link[i].diagonal) << i;
    }
  }
}

TEST(Model, AMassInertiaErrorScalesTheLinksMassesAndInertiasOnly) {
  const Model<double> m = Model<double>::of(robot::kArm), h = Model<double>::of(robot::kArm, 0.1);
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(h.link[i].mass, 1.1 * m.link[i].mass, 1e-12) << i;
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(h.link[i].inertia(a), 1.1 * m.link[i].inertia(a), 1e-15) << i;
      EXPECT_NEAR(h.link[i].products(a), 1.1 * m.link[i].products(a), 1e-15) << i;
      EXPECT_EQ(h.link[i].com(a), m.link[i].com(a)) << i;  // where the mass is: unchanged
    }
    EXPECT_EQ(h.link[i].R, m.link[i].R) << i;
    EXPECT_EQ(h.link[i].p, m.link[i].p) << i;
    EXPECT_EQ(h.armature(i), m.armature(i)) << i;  // the motors' inertia: not the links'
    const double G = robot::kArm.links[i].gear_ratio;
    EXPECT_NEAR(m.armature(i), G * G * robot::kArm.links[i].motor_inertia, 1e-15) << i;
  }
  EXPECT_EQ(h.gravity, m.gravity);
}

// A link with products of inertia is rotated through its tensor's Cholesky factor (Model::cholesky_root,
// rotated_full_inertia): L L^T is the tensor, and B B^T (B = R L) is R I R^T formed directly, for random
// positive-definite tensors of the sizes an arm's links have and random rotations.
TEST(Model, ARotatedFullInertiaIsRTimesTheTensorTimesRTransposed) {
  std::mt19937 rng(55);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int n = 0; n < 500; ++n) {
    Mat3<double> G;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) G(r, c) = u(rng);
    const double size = std::pow(10.0, -4 + 3 * (u(rng) + 1) / 2);  // 1e-4 .. 0.03 kg m^2
    const Mat3<double> I = size * (G * G.transpose() + 0.05 * Mat3<double>::Identity());
    const double t[6] = {I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)};
    Vec3<double> d, l;
    Model<double>::cholesky_root(t, 1.0, d, l);
    Mat3<double> L;
    L << d(0), 0, 0, l(0), d(1), 0, l(1), l(2), d(2);
    EXPECT_LE((L * L.transpose() - I).cwiseAbs().maxCoeff(), 1e-15 * size * 100) << n;
    const Mat3<double> R = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    Mat3<double> Ic;
    rotated_full_inertia(R, d, l, Ic);
    const double err = (Ic - R * I * R.transpose()).cwiseAbs().maxCoeff() / size;
    worst = std::max(worst, err);
    EXPECT_EQ(Ic, Ic.transpose()) << n;
  }
  std::printf("rotated inertia through the Cholesky factor against R I R^T: relative %.1e\n", worst);
  EXPECT_LE(worst, 1e-13);
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
