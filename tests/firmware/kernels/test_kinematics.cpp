// The kinematics (osc/kernels/kinematics.hpp) on random non-singular states (props_fixture.hpp): the
// analytic Jacobian and analytic Jdot qd against central finite differences of x(q) and Ja(q); E(phi)
// against the angular velocity of R(phi(t)), and E^{-1} its inverse.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <random>

#include "osc/kernels/kinematics.hpp"
#include "props_fixture.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST_F(Props, AnalyticJacobianAndJdotMatchFiniteDifferences) {
  double worst_J = 0, worst_Jd = 0;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(1.0);
    const Mat3<double> R_ref = reference_for(k, q);
    update(q, R_ref);
    const Mat6<double> Ja = os.Ja;
    // dx/dq by central differences of operational_coordinates.
    Mat6<double> fd;
    for (int j = 0; j < kDof; ++j) {
      const Vec6<double> e = Vec6<double>::Unit(j) * kH;
      fd.col(j) = (x_of(q + e, R_ref) - x_of(q - e, R_ref)) / (2 * kH);
    }
    worst_J = std::max(worst_J, (fd - Ja).norm() / Ja.norm());
    // d/dt (Ja(q + t qd)) qd at t = 0, R_ref fixed.
    update(q + kH * qd, R_ref);
    const Mat6<double> Jp = os.Ja;
    update(q - kH * qd, R_ref);
    const Mat6<double> Jm = os.Ja;
    const Vec6<double> jd_fd = (Jp - Jm) / (2 * kH) * qd;
    update(q, R_ref);
    Vec6<double> jd;
    {
      NoMalloc guard;
      jd = analytic_jdot_qd(model, data, os, qd);
    }
    worst_Jd = std::max(worst_Jd, (jd_fd - jd).norm() / std::max(jd.norm(), 1e-3));
  }
  std::printf("analytic Jacobian vs central differences: %.2e; analytic Jdot qd: %.2e (relative)\n", worst_J, worst_Jd);
  EXPECT_LT(worst_J, 1e-7);
  EXPECT_LT(worst_Jd, 1e-6);
}

// E(phi) (phi_rate_to_angular) against the angular velocity of R(phi(t)) = Rz Ry Rx by central
// differences, w^ = R_dot R^T; and E^{-1} (angular_to_phi_rate) its inverse.
TEST(OrientationRates, EMapsRollPitchYawRatesToTheAngularVelocity) {
  const auto R = [](const Vec3<double>& p) {
    return Mat3<double>(Eigen::AngleAxisd(p(2), Vec3<double>::UnitZ()) *
                        Eigen::AngleAxisd(p(1), Vec3<double>::UnitY()) *
                        Eigen::AngleAxisd(p(0), Vec3<double>::UnitX()));
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  for (int k = 0; k < 50; ++k) {
    const Vec3<double> phi(u(rng), u(rng), u(rng)), rate(u(rng), u(rng), u(rng));
    const double h = 1e-6;
    const Mat3<double> W = (R(phi + h * rate) - R(phi - h * rate)) / (2 * h) * R(phi).transpose();
    const Vec3<double> w(W(2, 1), W(0, 2), W(1, 0));
    EXPECT_LE((phi_rate_to_angular<double>(phi) * rate - w).norm(), 1e-8) << k;
    EXPECT_LE((angular_to_phi_rate<double>(phi) * phi_rate_to_angular<double>(phi) - Mat3<double>::Identity()).norm(),
              1e-12)
        << k;
  }
}

// E^{-1} w with its zeros and one skipped (phi_rates_of, analytic_jacobian): the product E.Einv * w forms, bit for
// bit, in double, float and fixed point (in fixed point both round each entry once).
template <class S>
void expect_phi_rates_are_the_product() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.4, 1.4);
  for (int k = 0; k < 200; ++k) {
    const Vec3<S> phi(S(u(rng)), S(u(rng)), S(u(rng)));
    const PhiRate<S> E = phi_rate(phi);
    const Vec3<S> w(S(u(rng)), S(u(rng)), S(u(rng)));
    const Vec3<S> product = E.Einv * w, skipped = phi_rates_of(E, w);
    for (int r = 0; r < 3; ++r) EXPECT_TRUE(product(r) == skipped(r)) << k << " " << r;
    Mat6<S> J;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) J(r, c) = S(u(rng));
    Mat6<S> Ja;
    analytic_jacobian(J, E, Ja);
    Mat6<S> expect = J;
    expect.template bottomRows<3>() = E.Einv * J.template bottomRows<3>();
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) EXPECT_TRUE(Ja(r, c) == expect(r, c)) << k << " " << r << " " << c;
  }
}
TEST(OrientationRates, TheRatesWithoutEInversesZerosAreItsProductBitForBit) {
  expect_phi_rates_are_the_product<double>();
  expect_phi_rates_are_the_product<float>();
  expect_phi_rates_are_the_product<Fixed>();
}

}  // namespace
