// The task's I/O map (osc/runtime/io.hpp, IoMap): encoder counts to joint angles and joint torques
// to the motors' channels through a drive train's coupling, against the matrices written out from
// the published wrist coupling (../shared/reference/puma560.md section 9), in double, float and
// fixed point; the monitors' channel-wise set-up (osc/runtime/monitors.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "osc/runtime/monitors.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

using M6 = Eigen::Matrix<double, 6, 6>;
using V6 = Vec6<double>;

/// The published coupling written out by hand (Trident wristCouplingG): q5 = e5 - 0.0139037 e4,
/// q6 = e6 + 0.0130401 e4 - 0.180556 e5.
M6 published_coupling() {
  M6 C = M6::Identity();
  C(4, 3) = -0.0139037;
  C(5, 3) = 0.0130401;
  C(5, 4) = -0.180556;
  return C;
}

/// The arm's coupled drive train in the scalar S, its matrix written out, and the start pose.
template <class S>
struct CoupledDrive {
  const EncoderMap& map = robot::kDriveTrain.encoders;
  const IoMap<S> io = IoMap<S>::of(map);
  const M6 C = published_coupling();
  const V6 q0 = joint_vector<double>(robot::kQStart);
};

template <class S>
class IoMaps : public ::testing::Test {};
using Scalars = ::testing::Types<double, float, Fixed>;
TYPED_TEST_SUITE(IoMaps, Scalars);

TEST(IoMap, TheDescriptionHoldsThePublishedCouplingAndScales) {
  OSC_PUMA_ONLY();
  const EncoderMap& map = robot::kDriveTrain.encoders;
  M6 C = M6::Identity();
  for (int k = 0; k < map.coupling_terms; ++k) C(map.coupling[k].row, map.coupling[k].col) += map.coupling[k].c;
  EXPECT_EQ(C, published_coupling());
  // Counts per motor revolution: 1000 on J1 and J3-J6, about 797 on J2 (a 200-line encoder).
  for (int i = 0; i < kDof; ++i) {
    const double per_rev = map.counts_per_rad[i] * 2 * kPi / std::abs(robot::kArm.links[i].gear_ratio);
    EXPECT_NEAR(per_rev, i == 1 ? 797 : 1000, i == 1 ? 3 : 2) << i;
  }
}

TEST(IoMap, TheInverseIsTheCouplingsInverse) {
  OSC_PUMA_ONLY();
  const IoMap<double> io = IoMap<double>::of(robot::kDriveTrain.encoders);
  M6 inv;
  for (int i = 0; i < kDof; ++i)
    for (int j = 0; j < kDof; ++j) inv(i, j) = io.inverse[i][j];
  EXPECT_LT((published_coupling() * inv - M6::Identity()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(io.drives.terms, 3);  // C^-1 has the same three off-diagonal places
}

TYPED_TEST(IoMaps, UncoupledMapsAreTodaysPerJointConversionBitForBit) {
  using S = TypeParam;
  const IoMap<S> io = IoMap<S>::of(robot::kEncodersUniform);
  EXPECT_FALSE(io.coupled());
  const Vec6<S> q0 = joint_vector<S>(robot::kQStart);
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::int32_t> u(-200000, 200000);
  for (int k = 0; k < 1000; ++k) {
    std::int32_t counts[kDof];
    for (auto& c : counts) c = u(rng);
    const Vec6<S> q = angles_from_counts(q0, io, counts);
    for (int i = 0; i < kDof; ++i) ASSERT_EQ(q(i), counts_to_angle<S>(i, counts[i], q0(i))) << i;
  }
}

TYPED_TEST(IoMaps, CoupledCountsGiveTheJointAnglesOfTheWrittenOutMatrix) {
  OSC_PUMA_ONLY();
  using S = TypeParam;
  const CoupledDrive<S> drive;
  const auto& [map, io, C, q0] = drive;
  ASSERT_TRUE(io.coupled());
  const double tol = std::is_same_v<S, double> ? 1e-12 : 2e-5;  // float: 24 bits; Q12.19: 2^-19 per term
  std::mt19937 rng(4);
  std::uniform_int_distribution<std::int32_t> u(-40000, 40000);
  double worst = 0;
  for (int k = 0; k < 1000; ++k) {
    std::int32_t counts[kDof];
    V6 e;
    for (int i = 0; i < kDof; ++i) counts[i] = u(rng), e(i) = counts[i] / map.counts_per_rad[i];
    const V6 expect = q0 + C * e;
    const Vec6<S> q = angles_from_counts(Vec6<S>(q0.template cast<S>()), io, counts);
    for (int i = 0; i < kDof; ++i) worst = std::max(worst, std::abs(static_cast<double>(q(i)) - expect(i)));
  }
  std::printf("coupled counts -> angles, worst error: %.3g rad\n", worst);
  EXPECT_LT(worst, tol);
}

// One joint <- motor map (joint_from_motor): the angles of counts are q0 + C e by it, bit for bit, and
// homing's correction through it (finish_homing: the encoders' zero moved by C de, the motors by de)
// gives the angles of the corrected motor angles: q0 + C (e + de), against the written-out matrix.
TYPED_TEST(IoMaps, HomingsCorrectionAndTheAnglesOfCountsAreOneMap) {
  OSC_PUMA_ONLY();
  using S = TypeParam;
  const CoupledDrive<S> drive;
  const auto& [map, io, C, q0] = drive;
  ASSERT_TRUE(io.coupled());
  const Vec6<S> q0_s = q0.template cast<S>();
  const double tol = std::is_same_v<S, double> ? 1e-12 : 4e-5;
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> u(-40000, 40000), turn(-2000, 2000);
  for (int k = 0; k < 500; ++k) {
    std::int32_t counts[kDof], shifted[kDof];
    V6 e, de;
    Vec6<S> e_s, de_s;
    for (int i = 0; i < kDof; ++i) {
      counts[i] = u(rng);
      const std::int32_t d = turn(rng);  // a correction of whole counts
      shifted[i] = counts[i] + d;
      e(i) = counts[i] / map.counts_per_rad[i], de(i) = d / map.counts_per_rad[i];
      e_s(i) = math::quotient<S>(counts[i], io.counts_per_rad(i));
      de_s(i) = math::quotient<S>(d, io.counts_per_rad(i));
    }
    const Vec6<S> q = angles_from_counts(q0_s, io, counts);
    const Vec6<S> by_map = joint_from_motor(io, e_s, q0_s);
    for (int i = 0; i < kDof; ++i) ASSERT_EQ(q(i), by_map(i)) << i;  // the same sums, in the same order
    const V6 ce = joint_from_motor(io, e_s).template cast<double>();
    ASSERT_LT((ce - C * e).cwiseAbs().maxCoeff(), tol);
    // Homing's correction de: the zero moved (q0 + C de), the same counts.
    const Vec6<S> q_start = q0_s + joint_from_motor(io, de_s);
    const V6 homed = angles_from_counts(q_start, io, counts).template cast<double>();
    const V6 expect = q0 + C * (e + de);
    ASSERT_LT((homed - expect).cwiseAbs().maxCoeff(), tol) << k;
    // The same angles as the counts of the corrected motors from the old zero.
    const V6 moved = angles_from_counts(q0_s, io, shifted).template cast<double>();
    ASSERT_LT((homed - moved).cwiseAbs().maxCoeff(), 2 * tol) << k;
  }
}

TYPED_TEST(IoMaps, CountsToAnglesToCountsRoundTrips) {
  // The encoder side of the plant counts floor(e counts_per_rad) with e = C^-1 (q - q0); the
  // firmware's angles of those counts, counted again, give the same counts (at the lattice points
  // the counts stand for, within the scalar's rounding).
  using S = TypeParam;
  const EncoderMap& map = robot::kDriveTrain.encoders;
  const IoMap<double> io = IoMap<double>::of(map);
  const IoMap<S> io_s = IoMap<S>::of(map);
  const V6 q0 = joint_vector<double>(robot::kQStart);
  M6 inv;
  for (int i = 0; i < kDof; ++i)
    for (int j = 0; j < kDof; ++j) inv(i, j) = io.inverse[i][j];
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::int32_t> u(-40000, 40000);
  for (int k = 0; k < 1000; ++k) {
    std::int32_t counts[kDof];
    for (auto& c : counts) c = u(rng);
    const Vec6<S> q = angles_from_counts(Vec6<S>(q0.cast<S>()), io_s, counts);
    const V6 e = inv * (q.template cast<double>() - q0);
    for (int i = 0; i < kDof; ++i) ASSERT_EQ(std::lround(e(i) * map.counts_per_rad[i]), counts[i]) << i << " " << k;
  }
}

TYPED_TEST(IoMaps, MotorTorquesAndRatesAreTheTransposeAndTheInverse) {
  OSC_PUMA_ONLY();
  using S = TypeParam;
  const IoMap<S> io = IoMap<S>::of(robot::kDriveTrain.encoders);
  const M6 C = published_coupling();
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-20, 20);
  const double tol = std::is_same_v<S, double> ? 1e-13 : 2e-4;
  for (int k = 0; k < 200; ++k) {
    V6 tau, qd;
    for (int i = 0; i < kDof; ++i) tau(i) = u(rng), qd(i) = u(rng) / 10;
    const V6 tm = motor_torques(io, Vec6<S>(tau.cast<S>())).template cast<double>();
    const V6 em = motor_rates(io, Vec6<S>(qd.cast<S>())).template cast<double>();
    EXPECT_LT((tm - C.transpose() * tau).cwiseAbs().maxCoeff(), tol);
    EXPECT_LT((C * em - qd).cwiseAbs().maxCoeff(), tol);
    // The same power on both sides of the gears: tau_m . e_dot = tau . q_dot.
    EXPECT_NEAR(tm.dot(em), tau.dot(qd), 50 * tol);
  }
}

TEST(IoMap, CoupledChannelsRangeAndStepCoverTheJointsBox) {
  // Every pose in the joints' box of limits (corners included) reads within each channel's range;
  // a pose beyond the box plus the margin on one joint reads outside on its own channel.
  const IoMap<double> io = IoMap<double>::of(robot::kDriveTrain.encoders);
  const EncoderMap& map = robot::kDriveTrain.encoders;
  double q0[kDof];
  for (int i = 0; i < kDof; ++i) q0[i] = robot::kQStart[i];
  EncoderRangeMonitor range;
  EncoderJumpMonitor jump;
  for (int i = 0; i < kDof; ++i)
    range.set(i, q0, map.counts_per_rad[i], io.inverse), jump.set(i, map.counts_per_rad[i], io.inverse);
  M6 inv;
  for (int i = 0; i < kDof; ++i)
    for (int j = 0; j < kDof; ++j) inv(i, j) = io.inverse[i][j];
  auto counts_of = [&](const V6& q, std::int32_t out[kDof]) {
    const V6 e = inv * (q - joint_vector<double>(robot::kQStart));
    for (int i = 0; i < kDof; ++i) out[i] = static_cast<std::int32_t>(std::floor(e(i) * map.counts_per_rad[i]));
  };
  for (int corner = 0; corner < 64; ++corner) {
    V6 q;
    for (int j = 0; j < kDof; ++j) q(j) = (corner >> j & 1) ? robot::kArm.q_max[j] : robot::kArm.q_min[j];
    std::int32_t c[kDof];
    counts_of(q, c);
    EXPECT_EQ(range.check(c), 0u) << corner;
  }
  for (int j = 0; j < kDof; ++j) {
    V6 q = joint_vector<double>(robot::kQStart);
    q(j) = robot::kArm.q_max[j] + params::kJointLimitMargin + 0.5;
    std::int32_t c[kDof];
    counts_of(q, c);
    EXPECT_EQ(range.check(c), kFaultEncoderRange) << j;
  }
  // The largest step per tick: motor 6 turns with q6_dot + 0.18 q5_dot (+ 0.015 q4_dot) at most.
  const double speed6 = robot::kDrives.max_joint_speed[5] +
                        std::abs(io.inverse[5][4]) * robot::kDrives.max_joint_speed[4] +
                        std::abs(io.inverse[5][3]) * robot::kDrives.max_joint_speed[3];
  EXPECT_EQ(jump.max_step[5], static_cast<std::int32_t>(speed6 * params::kDt * map.counts_per_rad[5]) + 1);
  if (io.coupled()) {  // the coupling adds the wrist's other motors' share (an uncoupled arm: the joint's own)
    EXPECT_GT(jump.max_step[5],
              static_cast<std::int32_t>(robot::kDrives.max_joint_speed[5] * params::kDt * map.counts_per_rad[5]) + 1);
  }
}

// A joint torque to its DAC code in each floating scalar (torque_to_code's one-comparison path): within half a
// code of torque x scale below the limit (rounded half away from zero), the scalars' codes a code apart at most,
// and saturated to the full code at and beyond the limit, a NaN to code 0, both flagged.
TEST(TorqueToCode, FloatAndDoubleRoundBelowTheLimitAndSaturateAtIt) {
  for (int i = 0; i < kDof; ++i) {
    const double limit = robot::kDrives.torque_limit[i], scale = kDacMaxCode / limit;
    for (int k = -12000; k <= 12000; ++k) {
      const double t = limit * k / 10000.0;
      std::int32_t cd = 7, cf = 7;
      const bool sd = torque_to_code(i, t, cd), sf = torque_to_code(i, static_cast<float>(t), cf);
      if (std::abs(t) < limit * (1 - 1e-6)) {
        EXPECT_FALSE(sd) << i << " " << t;
        EXPECT_FALSE(sf) << i << " " << t;
        EXPECT_LE(std::abs(cd - t * scale), 0.5 + 1e-9) << i << " " << t;
        EXPECT_LE(std::abs(cf - t * scale), 0.5 + 1e-2) << i << " " << t;
        EXPECT_LE(std::abs(cf - cd), 1) << i << " " << t;
        if (k != 0) {
          EXPECT_EQ(cd > 0, t > 0) << i << " " << t;
        }
      } else if (std::abs(t) >= limit) {
        EXPECT_TRUE(sd && sf) << i << " " << t;
        EXPECT_EQ(cd, t > 0 ? kDacMaxCode : -kDacMaxCode) << i << " " << t;
        EXPECT_EQ(cf, cd) << i << " " << t;
      }
    }
    std::int32_t c = 7;
    EXPECT_TRUE(torque_to_code(i, std::numeric_limits<float>::quiet_NaN(), c));
    EXPECT_EQ(c, 0);
    EXPECT_TRUE(torque_to_code(i, std::numeric_limits<float>::infinity(), c));
    EXPECT_EQ(c, kDacMaxCode);
    EXPECT_TRUE(torque_to_code(i, -std::numeric_limits<float>::infinity(), c));
    EXPECT_EQ(c, -kDacMaxCode);
    EXPECT_TRUE(torque_to_code(i, -std::numeric_limits<double>::infinity(), c));
    EXPECT_EQ(c, -kDacMaxCode);
  }
}

}  // namespace
