// The payload check (osc/runtime/payload_check.hpp): a residual that is a payload's weight, from Orocos KDL's
// gravity torques of the arm with and without the payload (an independent model), is fitted as that weight in
// every scalar (its mass, its centre of mass's horizontal distance from frame 6's origin); a torque on one joint, or
// an external torque the residual tests use, is no weight.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <random>

#include "kdl_puma.hpp"
#include "monitor_fixtures.hpp"
#include "osc/kernels/kinematics.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/math/q_eigen.hpp"
#include "osc/runtime/payload_check.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;
using namespace osc::test;

namespace {

/// A point payload as issue 57's: 0.2-5 kg, its centre of mass within +-0.1 m of frame 6's origin per coordinate.
struct CheckPayloads {
  std::mt19937_64 rng{2057};
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  Payload next() {
    Payload b{};
    b.mass = 2.6 + 2.4 * u(rng);
    for (double& c : b.com) c = 0.1 * u(rng);
    return b;
  }
};

/// KDL's gravity torques of the arm with `b` at frame 6 less those without it: g_payload(q).
Vec6<double> kdl_payload_gravity(const Payload& b, const Vec6<double>& q) {
  const KDL::Vector g(0, 0, -robot::kArm.gravity);
  KDL::Chain with = test::puma560_chain();
  with.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), KDL::Frame::Identity(),
                               KDL::RigidBodyInertia(b.mass, KDL::Vector(b.com[0], b.com[1], b.com[2]))));
  KDL::JntArray g_with(kDof), g_without(kDof);
  KDL::ChainDynParam(with, g).JntToGravity(to_kdl(q), g_with);
  KDL::ChainDynParam(test::puma560_chain(), g).JntToGravity(to_kdl(q), g_without);
  return from_kdl(g_with) - from_kdl(g_without);
}

/// The payload's centre of mass's horizontal distance from frame 6's origin, from KDL's pose of frame 6.
double kdl_offset(const Payload& b, const Vec6<double>& q) {
  KDL::Frame F;
  KDL::ChainFkSolverPos_recursive(test::puma560_chain()).JntToCart(to_kdl(q), F);
  const KDL::Vector c = F.M * KDL::Vector(b.com[0], b.com[1], b.com[2]);
  return std::hypot(c.x(), c.y());
}

Mat6<double> frame6_jacobian(const Vec6<double>& q) {
  static const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  forward_kinematics(model, data, q);
  geometric_jacobian(data);
  return data.J;
}

template <class S>
FlangeWeight<S> fit_in(const Mat6<double>& J, const Vec6<double>& r) {
  return flange_weight<S>(J.cast<S>(), r.cast<S>());
}

}  // namespace

TEST(PayloadCheck, APayloadsWeightFromKdlIsFittedAsThatWeightInEveryScalar) {
  test::RandomStates rs;
  CheckPayloads payloads;
  double mass[3] = {}, offset[3] = {}, misfit[3] = {};
  int alone = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec6<double> q = rs.q_nonsingular();
    const Payload b = payloads.next();
    const Vec6<double> g = kdl_payload_gravity(b, q);
    const Mat6<double> J = frame6_jacobian(q);
    const double sign = k % 2 == 0 ? 1 : -1;  // set and not on the arm; on the arm and not set
    const double truth = kdl_offset(b, q);
    const FlangeWeight<double> wd = fit_in<double>(J, sign * g);
    const FlangeWeight<float> wf = fit_in<float>(J, sign * g);
    const FlangeWeight<fixed::Q<19>> wq = fit_in<fixed::Q<19>>(J, sign * g);
    const double m[3] = {wd.mass, wf.mass, static_cast<double>(wq.mass)},
                 o[3] = {wd.offset, wf.offset, static_cast<double>(wq.offset)},
                 f[3] = {wd.misfit, wf.misfit, static_cast<double>(wq.misfit)};
    for (int s = 0; s < 3; ++s) {
      mass[s] = std::max(mass[s], std::abs(m[s] - sign * b.mass) / b.mass);
      offset[s] = std::max(offset[s], std::abs(o[s] - truth));
      misfit[s] = std::max(misfit[s], f[s]);
    }
    // Named, but where the weight loads one joint all but alone (a pose that cannot tell it from that joint's
    // drive or encoder): then everything else of the check holds.
    const bool one_joint = wd.spread < params::kPayloadSpread;
    alone += one_joint;
    EXPECT_EQ(payload_mismatch(wd), !one_joint) << k << ": " << wd.misfit << ", " << wd.spread;
    EXPECT_EQ(payload_mismatch(wf), !one_joint) << k;
    EXPECT_EQ(payload_mismatch(wq), static_cast<double>(wq.spread) >= params::kPayloadSpread) << k;
  }
  std::printf(
      "200 payloads against KDL's gravity, double / float / Q12.19: mass within %.1e / %.1e / %.1e; "
      "offset within %.1e / %.1e / %.1e m; misfit at most %.1e / %.1e / %.1e; on one joint all but alone "
      "(not named) %d\n",
      mass[0], mass[1], mass[2], offset[0], offset[1], offset[2], misfit[0], misfit[1], misfit[2], alone);
  EXPECT_LE(alone, 20);  // 10 % of the poses
  EXPECT_LE(mass[0], 1e-9);
  EXPECT_LE(offset[0], 1e-9);
  EXPECT_LE(misfit[0], 1e-12);
  EXPECT_LE(mass[1], 1e-4);
  EXPECT_LE(mass[2], 1e-3);
  EXPECT_LE(offset[2], 1e-3);
  EXPECT_LE(misfit[2], 1e-3);
}

// One joint's torque alone (a stuck encoder's, a drive's) is no weight at any of the poses; nor is the residual
// tests' external torque, nor 0.
TEST(PayloadCheck, ATorqueOnOneJointOrAContactsIsNoWeight) {
  test::RandomStates rs;
  double least = 1;
  int named = 0;
  for (int k = 0; k < 200; ++k) {
    const Mat6<double> J = frame6_jacobian(rs.q_nonsingular());
    for (int i = 0; i < kDof; ++i) {
      const FlangeWeight<double> w = fit_in<double>(J, 5 * Vec6<double>::Unit(i));
      least = std::min(least, w.misfit);
      named += payload_mismatch(w);
    }
    EXPECT_FALSE(payload_mismatch(fit_in<double>(J, closed_form_torque()))) << k;
  }
  std::printf("a torque on one joint, 200 poses: the least misfit %.3f; named a payload %d times\n", least, named);
  EXPECT_EQ(named, 0);
  EXPECT_FALSE(fit_in<double>(frame6_jacobian(rs.q_nonsingular()), Vec6<double>::Zero()).fitted);
}

namespace {

/// The residual monitor's rig (monitor_fixtures.hpp) held at the start pose while the drives apply the gravity the
/// arm has and the model's `weight` more or less (a payload set and not on the arm: its weight; on the arm, not
/// set: minus it), from the enable on or after `wait` ticks (-1: from the enable, without the step's Jacobian): the
/// fault and its tick (-1: none in 2000).
template <class S>
int payload_fault(ResidualRig<S>& rig, const Vec6<double>& weight, int wait, std::uint32_t& kind) {
  rig.m.armed = true;
  if (wait >= 0) rig.jacobian = true;
  const bool none[kDof] = {};
  kind = 0;
  for (int n = 0; n < wait + 2000; ++n)
    if ((kind = rig.step(n < wait ? Vec6<double>::Zero() : weight, none, false)) != 0) return n;
  return -1;
}

}  // namespace

// 2.5 kg at (0.03, -0.03, 0.09) m (payload_stale's) set and not on the arm: KDL's weight of it at the start pose. The
// residual monitor names it payload_mismatch within 50 ms of the enable and records the weight its residual then
// holds (filtered: J2 and J3's at 1 - e^(-50 t) of the truth, 0.67 at 22 ms; J5's at 1 - e^(-20 t)); the same weight a
// second after the enable is no payload's (a contact then: collision); without the step's Jacobian, no payload either.
TYPED_TEST(Monitors, AWeightAtTheEnableIsAPayloadMismatch) {
  using S = TypeParam;
  Payload b{};
  b.mass = 2.5;
  b.com[0] = 0.03, b.com[1] = -0.03, b.com[2] = 0.09;
  const Vec6<double> weight = kdl_payload_gravity(b, joint_vector<double>(robot::kQStart));
  ResidualRig<S> rig;
  std::uint32_t kind = 0;
  const int at = payload_fault(rig, weight, 0, kind);
  const double mass = static_cast<double>(rig.m.flange.mass);
  std::printf("2.5 kg: %s at tick %d, %.3f kg, %.1f mm off, misfit %.4f\n", fault_name(kind), at, mass,
              1e3 * static_cast<double>(rig.m.flange.offset), static_cast<double>(rig.m.flange.misfit));
  EXPECT_EQ(kind, kFaultPayloadMismatch);
  EXPECT_GE(at, 0);
  EXPECT_LE(at, 50);
  EXPECT_GE(mass, 0.6 * 2.5);
  EXPECT_LE(mass, 2.5);
  ResidualRig<S> late;
  EXPECT_GE(payload_fault(late, weight, params::kPayloadCheckTicks + 10, kind), 0);
  EXPECT_NE(kind, kFaultPayloadMismatch) << fault_name(kind);
  ResidualRig<S> blind;
  EXPECT_GE(payload_fault(blind, weight, -1, kind), 0);
  EXPECT_NE(kind, kFaultPayloadMismatch) << fault_name(kind);
}

// The held-pose rule (ResidualMonitor::decide): the rig held at the start pose from the enable (ResidualMonitor::
// holding), the drives short of what was asked of them (or a load the model lacks) by 20 N m on J3 alone, or by 30 and
// -15 N m on J2 and J3 (no weight's shape). Each is encoder_stuck when the arm has not held since the enable, or when
// the finding comes after the first second. Held, within it: one joint's is drive_fault, two joints' payload_mismatch;
// with the drives measured (the drive check ran), its suspect decides: a suspect drive, drive_fault, none,
// payload_mismatch.
TYPED_TEST(Monitors, AFindingAtAPoseHeldSinceTheEnableIsNoStuckEncoder) {
  using S = TypeParam;
  Vec6<double> one = Vec6<double>::Zero(), two = Vec6<double>::Zero();
  one(2) = 20;
  two(1) = 30, two(2) = -15;
  const auto kind_of = [](const Vec6<double>& torque, bool holding, int wait, bool checked, std::uint8_t suspect) {
    ResidualRig<S> rig;
    rig.m.holding = holding;
    rig.m.drives_checked = checked;
    rig.m.drive_suspect = suspect;
    std::uint32_t kind = 0;
    EXPECT_GE(payload_fault(rig, torque, wait, kind), 0);
    return kind;
  };
  EXPECT_EQ(kind_of(one, false, 0, false, 0), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(two, false, 0, false, 0), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(one, true, 1100, false, 0), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(one, true, 0, false, 0), kFaultDriveFault);
  EXPECT_EQ(kind_of(two, true, 0, false, 0), kFaultPayloadMismatch);
  EXPECT_EQ(kind_of(one, true, 0, true, 0), kFaultPayloadMismatch);
  EXPECT_EQ(kind_of(one, true, 0, true, 1u << 2), kFaultDriveFault);
  EXPECT_EQ(kind_of(two, true, 0, true, 1u << 1), kFaultDriveFault);
}

// The rule of a joint moved off its reference (ResidualMonitor::off_reference), in the rig with a motion commanded
// (not holding): the drives short by 20 N m on J3 alone, or by -8 and 20 N m on J2 and J3 (no weight's shape), while
// J2 and J3 count `m` counts the way of their shortfall after the enable (pushed off by a load the drives do not
// hold), one every 10 ticks, and the step's tracking error puts each one's reference `toward` counts that way from its
// reading (the operational space at the start pose, e = Ja dq; negative: back). Counted 4 with the reference 4 back,
// within the first second: one joint's is drive_fault, two joints' payload_mismatch. The reference where the reading
// is or further on, back by 1 count only, 2 counts counted (the margin's), after the first second, or without the
// step's operational space: encoder_stuck.
TYPED_TEST(Monitors, AJointMovedOffItsReferenceSinceTheEnableIsNoStuckEncoder) {
  using S = TypeParam;
  Model<S> model = Model<S>::of(robot::kArm);
  Data<S> data;
  ArmOpSpace<S> os;
  forward_kinematics(model, data, joint_vector<S>(robot::kQStart));
  opspace_update(model, data, os, joint_vector<S>(robot::kQStart), data.R[kDof]);
  Vec6<double> one = Vec6<double>::Zero(), two = Vec6<double>::Zero();
  one(2) = 20;
  two(1) = -8, two(2) = 20;
  const auto kind_of = [&](const Vec6<double>& torque, int m, double toward, int wait, bool with_os) {
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.jacobian = true;
    Vec6<S> dq = Vec6<S>::Zero();
    for (const int j : {1, 2}) dq(j) = static_cast<S>((torque(j) < 0 ? -toward : toward) / counts_per_rad(j));
    rig.e = os.Ja * dq;
    if (with_os) rig.os = &os;
    std::uint32_t kind = 0;
    for (int n = 0; n < wait + 2000 && kind == 0; ++n) {
      const int k = n - wait;
      const bool count = k > 0 && k % 10 == 0 && k / 10 <= m;
      const bool counting[kDof] = {false, count, count, false, false, false};
      for (const int j : {1, 2})
        if (count && torque(j) < 0) rig.counts[j] -= 2;  // the rig counts up: one down
      kind = rig.step(k < 0 ? Vec6<double>::Zero() : torque, counting, false);
    }
    return kind;
  };
  EXPECT_EQ(kind_of(one, 4, -4, 0, true), kFaultDriveFault);
  EXPECT_EQ(kind_of(two, 4, -4, 0, true), kFaultPayloadMismatch);
  EXPECT_EQ(kind_of(one, 4, 0, 0, true), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(two, 4, 3, 0, true), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(one, 4, -1, 0, true), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(two, 2, -4, 0, true), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(one, 4, -4, 1100, true), kFaultEncoderStuck);
  EXPECT_EQ(kind_of(two, 4, -4, 0, false), kFaultEncoderStuck);
}

// residual_spread: the share of r's square off its largest joint, as a hand computation gives it, in every scalar.
TYPED_TEST(Monitors, TheResidualsSpreadIsItsShareOffItsLargestJoint) {
  using S = TypeParam;
  Vec6<S> r = Vec6<S>::Zero();
  EXPECT_EQ(residual_spread(r), S(0));
  r(1) = S(4);
  EXPECT_EQ(residual_spread(r), S(0));
  r(2) = S(-3);  // 9 of 25 off J2
  EXPECT_NEAR(static_cast<double>(residual_spread(r)), 9.0 / 25.0, 1e-4);
  r(4) = S(2);  // 13 of 29
  EXPECT_NEAR(static_cast<double>(residual_spread(r)), 13.0 / 29.0, 1e-4);
}

// flange_lever: at 2 000 random poses the flange's origin is never farther from joint i's axis than the lever less
// the payload's reach, and the farthest seen is within 20 % of it on the arm's joints (the bound is not loose); the
// wrist's axes pass through the flange's origin on the PUMA (its lever is the reach alone).
TEST(PayloadCheck, TheFlangeLeverBoundsTheFlangesDistanceFromEachAxis) {
  test::RandomStates rs;
  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  double farthest[kDof] = {};
  for (int k = 0; k < 2000; ++k) {
    forward_kinematics(model, data, rs.q_nonsingular());
    for (int i = 0; i < kDof; ++i) {
      const Vec3<double> d = data.o[kDof] - data.o[i], z = data.R[i].col(2);
      farthest[i] = std::max(farthest[i], (d - d.dot(z) * z).norm());
    }
  }
  const double reach = 1.7320508 * robot::kPayloadRating.com_reach;
  for (int i = 0; i < kDof; ++i) {
    std::printf("J%d: the flange at most %.3f m from the axis, the lever %.3f m (less the reach)\n", i + 1, farthest[i],
                flange_lever(i) - reach);
    EXPECT_LE(farthest[i], flange_lever(i) - reach + 1e-9) << i;
    if (flange_lever(i) - reach > 1e-3) {
      EXPECT_GE(farthest[i], 0.8 * (flange_lever(i) - reach)) << i;
    }
  }
}
