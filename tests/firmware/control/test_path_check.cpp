// The path check (osc/control/path_check.hpp) against Orocos KDL 1.5.1 on the build's arm, its chain read
// from the arm's own URDF and sheet (tests/support/kdl_arm.hpp: urdfdom and yaml-cpp, not the generator):
// targets built by KDL's forward kinematics, the end joint angles put through KDL's forward kinematics
// again and compared with the target's own joint angles and with KDL's inverse kinematics
// (ChainIkSolverPos_LMA); the orientation coordinates' singularity at the sample where KDL's solution
// shows it; float and Q12.19 against double. On the PUMA 560 also its own geometry (OSC_PUMA_ONLY): each
// failure (a joint limit on the way, the wrist singularity at a sample and between two, a target out of
// reach) at the sample where the path's closed form shows it, and the fixed-point flags of the caller
// kept. The UR5e's singular poses are refused by test_motion_sim (AMoveIntoEachSingularity...).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <memory>
#include <random>

#include "kdl_arm.hpp"
#include "kdl_puma.hpp"
#include "osc/control/path_check.hpp"
#include "osc/math/fixed.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;

namespace {

constexpr int N = params::kPathCheckPoints;
const CartesianLimits<double> kLim = CartesianLimits<double>::defaults();

/// The build's arm from its URDF and sheet (not the generated table): its last segment is frame 6.
const KDL::Chain& urdf_chain() {
  static const KDL::Chain chain = test::urdf_arm_chain(OSC_ARM_SHEET);
  return chain;
}

/// The frame-6 pose of q by KDL's forward kinematics.
Pose<double> kdl_pose(const Vec6<double>& q) {
  KDL::ChainFkSolverPos_recursive fk(urdf_chain());
  KDL::Frame F;
  EXPECT_GE(fk.JntToCart(to_kdl(q), F), 0);
  Pose<double> p;
  for (int r = 0; r < 3; ++r) {
    p.p(r) = F.p(r);
    for (int c = 0; c < 3; ++c) p.R(r, c) = F.M(r, c);
  }
  return p;
}

/// The angle between two rotations [rad] (from the sine: accurate for small angles).
double rotation_error(const Mat3<double>& R, const Mat3<double>& Rd) {
  const Vec3<double> w = 0.5 * (R.col(0).cross(Rd.col(0)) + R.col(1).cross(Rd.col(1)) + R.col(2).cross(Rd.col(2)));
  const double c = 0.5 * ((R.transpose() * Rd).trace() - 1);
  return std::atan2(w.norm(), c);
}

/// KDL's inverse kinematics (Levenberg-Marquardt, equal weights) of a pose from q_init; false when
/// its solution misses the pose by more than 1e-7 m or 1e-6 rad (its accuracy here: the solver
/// stops on its joint increments before its error criterion, about 1e-7 rad in orientation).
bool kdl_ik(const Pose<double>& target, const Vec6<double>& q_init, Vec6<double>& q) {
  KDL::ChainIkSolverPos_LMA ik(urdf_chain(), Vec6<double>::Ones(), 1e-24, 1000);
  KDL::Frame F;
  for (int r = 0; r < 3; ++r) {
    F.p(r) = target.p(r);
    for (int c = 0; c < 3; ++c) F.M(r, c) = target.R(r, c);
  }
  KDL::JntArray out(kDof);
  ik.CartToJnt(to_kdl(q_init), F, out);
  q = from_kdl(out);
  const Pose<double> reached = kdl_pose(q);
  return (reached.p - target.p).norm() < 1e-7 && rotation_error(reached.R, target.R) < 1e-6;
}

/// The smallest distance of a joint to its nearer limit [rad].
double clearance(const Vec6<double>& q) {
  double c = 1e9;
  for (int i = 0; i < kDof; ++i) c = std::min({c, q(i) - robot::kArm.q_min[i], robot::kArm.q_max[i] - q(i)});
  return c;
}

/// The move from the pose of q_a to that of q_b, planned in scalar S, and its check from q_a.
template <class S>
struct MoveCheck {
  CartesianMove<S> move;
  PathCheck<S> check;
};

template <class S>
MoveCheck<S> check_move(const Pose<double>& a, const Pose<double>& b, const Mat3<double>& R_ref,
                        const Vec6<double>& seed) {
  static const Model<S> model = Model<S>::of(robot::kArm);
  static const std::unique_ptr<Data<S>> data = std::make_unique<Data<S>>();
  const auto cast = [](const Pose<double>& p) { return Pose<S>{p.p.cast<S>(), p.R.cast<S>()}; };
  MoveCheck<S> r;
  EXPECT_EQ(r.move.plan(cast(a), cast(b), CartesianLimits<S>::defaults(), R_ref.cast<S>()), ProfileStatus::kOk);
  const Vec6<S> q = seed.cast<S>();
  const Mat3<S> Rr = R_ref.cast<S>();
  test::NoMalloc guard;
  r.check = check_path<S>(model, *data, r.move, Rr, q);
  return r;
}

template <class S>
MoveCheck<S> check_joint_move(const Vec6<double>& q_a, const Vec6<double>& q_b) {
  const Pose<double> a = kdl_pose(q_a), b = kdl_pose(q_b);
  return check_move<S>(a, b, a.R, q_a);
}

/// The samples' poses of a move (as check_path takes them: the end pose last).
Pose<double> sample_pose(const CartesianMove<double>& m, int i) {
  return i == N ? m.end() : m.pose_at(m.duration() * i / N);
}

/// The first sample of the move at which KDL's inverse kinematics, followed from q sample by
/// sample, puts a joint within the margin of its limit; -1 when none does.
int kdl_first_out_of_limits(const CartesianMove<double>& m, Vec6<double> q) {
  for (int i = 0; i <= N; ++i) {
    Vec6<double> next;
    EXPECT_TRUE(kdl_ik(sample_pose(m, i), q, next)) << i;
    q = next;
    if (clearance(q) < params::kWorkspaceMargin) return i;
  }
  return -1;
}

/// The reciprocal condition the controller tests at q (the analytic Jacobian's, relative to R_ref).
double controller_rcond(const Vec6<double>& q, const Mat3<double>& R_ref) {
  static const Model<double> model = Model<double>::of(robot::kArm);
  static const std::unique_ptr<Data<double>> data = std::make_unique<Data<double>>();
  forward_kinematics(model, *data, q);
  geometric_jacobian(*data);
  ArmJacobianFactor<double> Jf;  // a fresh factor: its rcond exact (the pivoted LU's too)
  Jf.compute(analytic_jacobian(data->J, orientation_coordinates<double>(data->R[kDof], R_ref)));
  return Jf.rcond;
}

/// Pairs of joint angles q_a, q_b = q_a + up to 0.5 rad per joint, each 0.4 rad inside the limits,
/// and the straight line between them in joint space away from the singularities: the controller's
/// rcond at least 3 kPathMinRcond at 21 points of it. Its two ends are then on the same
/// inverse-kinematics branch (no singularity between them). The move follows the straight line
/// between their poses, not this one, and could still meet a singularity; none of the first 300
/// pairs of this seed does (all pass the check).
struct Pairs {
  std::mt19937_64 rng{2024};
  std::uniform_real_distribution<double> u{-1.0, 1.0};

  bool good(const Vec6<double>& qa, const Vec6<double>& qb) {
    if (clearance(qa) < 0.4 || clearance(qb) < 0.4) return false;
    const Mat3<double> R_ref = kdl_pose(qa).R;
    for (int k = 0; k <= 20; ++k)
      if (controller_rcond(qa + (qb - qa) * (k / 20.0), R_ref) < 3 * params::kPathMinRcond) return false;
    return true;
  }
  void next(Vec6<double>& qa, Vec6<double>& qb) {
    do {
      for (int i = 0; i < kDof; ++i) {
        const double lo = robot::kArm.q_min[i], hi = robot::kArm.q_max[i];
        qa(i) = lo + (hi - lo) * 0.5 * (u(rng) + 1.0);
        qb(i) = qa(i) + 0.5 * u(rng);
      }
    } while (!good(qa, qb));
  }
};

constexpr int kPairs = 40;

TEST(CartesianMove, PoseAtIsThePoseOfTheReference) {
  const Pose<double> a{{0.5, -0.1, 0.3}, rpy_rotation<double>({0.1, 0.2, -0.3})};
  const Pose<double> b{{0.4, 0.2, 0.35}, rpy_rotation<double>({-0.4, 0.3, 0.8})};
  const Mat3<double> R_ref = rpy_rotation<double>({0.2, -0.1, 0.4});
  CartesianMove<double> m;
  ASSERT_EQ(m.plan(a, b, kLim, R_ref), ProfileStatus::kOk);
  for (double t = -0.1; t < m.duration() + 0.2; t += 0.05) {
    const Desired<double> d = m.at(t);
    const Pose<double> p = m.pose_at(t);
    EXPECT_LE((p.p - d.x.head<3>()).norm(), 1e-15) << t;
    EXPECT_LE((p.R - rpy_rotation<double>(d.x.tail<3>()) * R_ref).norm(), 1e-12) << t;
  }
  EXPECT_LE((m.pose_at(m.duration()).p - b.p).norm(), 1e-12);
  EXPECT_LE(rotation_error(m.pose_at(m.duration()).R, b.R), 1e-9);
}

// The chain read from the URDF and the sheet ends at the firmware's frame 6 (the kernels' forward
// kinematics on the generated table): what every comparison below rests on.
TEST(PathCheck, TheUrdfChainEndsAtFrameSix) {
  ASSERT_EQ(urdf_chain().getNrOfJoints(), static_cast<unsigned>(kDof));
  const Model<double> model = Model<double>::of(robot::kArm);
  const auto data = std::make_unique<Data<double>>();
  Pairs pairs;
  double worst_p = 0, worst_R = 0;
  for (int k = 0; k < 20; ++k) {
    Vec6<double> qa, qb;
    pairs.next(qa, qb);
    forward_kinematics(model, *data, qa);
    const Pose<double> p = kdl_pose(qa);
    worst_p = std::max(worst_p, (p.p - data->o[kDof]).norm());
    worst_R = std::max(worst_R, rotation_error(p.R, data->R[kDof]));
  }
  EXPECT_LE(worst_p, 1e-12);
  EXPECT_LE(worst_R, 1e-12);
}

// The end angles reproduce the target (KDL's forward kinematics), equal the target's own angles
// (the seed's branch) and KDL's inverse kinematics from the seed.
TEST(PathCheck, EndAnglesReachTheTargetOnTheSeedsBranch) {
  Pairs pairs;
  double worst_p = 0, worst_R = 0, worst_q = 0, worst_kdl = 0;
  for (int k = 0; k < kPairs; ++k) {
    Vec6<double> qa, qb;
    pairs.next(qa, qb);
    const MoveCheck<double> r = check_joint_move<double>(qa, qb);
    ASSERT_EQ(r.check.status, PathStatus::kOk) << k << ": sample " << r.check.sample;
    EXPECT_EQ(r.check.sample, -1);
    EXPECT_GE(r.check.clearance, params::kWorkspaceMargin);
    EXPECT_GE(r.check.rcond, params::kPathMinRcond);
    const Pose<double> target = kdl_pose(qb), reached = kdl_pose(r.check.q_end);
    worst_p = std::max(worst_p, (reached.p - target.p).norm());
    worst_R = std::max(worst_R, rotation_error(reached.R, target.R));
    worst_q = std::max(worst_q, (r.check.q_end - qb).cwiseAbs().maxCoeff());
    Vec6<double> q_kdl;
    ASSERT_TRUE(kdl_ik(target, qa, q_kdl)) << k;
    worst_kdl = std::max(worst_kdl, (r.check.q_end - q_kdl).cwiseAbs().maxCoeff());
  }
  std::printf("%d moves: end pose error %.2e m, %.2e rad; end angles vs target's %.2e rad, vs KDL's IK %.2e rad\n",
              kPairs, worst_p, worst_R, worst_q, worst_kdl);
  EXPECT_LE(worst_p, 1e-6);
  EXPECT_LE(worst_R, 1e-6);
  EXPECT_LE(worst_q, 1e-6);
  EXPECT_LE(worst_kdl, 1e-5);  // KDL's own accuracy (kdl_ik)
}

// A seed a tracking error away from the move's start (2 cm and 0.02 rad per joint): the first
// sample's Newton steps bring it onto the path; the end is the same.
TEST(PathCheck, ConvergesFromASeedOffTheStart) {
  Pairs pairs;
  for (int k = 0; k < 10; ++k) {
    Vec6<double> qa, qb;
    pairs.next(qa, qb);
    const Pose<double> a = kdl_pose(qa), b = kdl_pose(qb);
    const Vec6<double> seed = qa + 0.02 * Vec6<double>(1, -1, 1, -1, 1, -1);
    const MoveCheck<double> r = check_move<double>(a, b, a.R, seed);
    ASSERT_EQ(r.check.status, PathStatus::kOk) << k;
    EXPECT_LE((r.check.q_end - qb).cwiseAbs().maxCoeff(), 1e-9) << k;
  }
}

// Rotating the upper arm at a fixed elbow moves the wrist centre along a chord that passes the
// shoulder closer than the elbow can fold within its limit: joint 3 passes -225 deg on the way
// (to -238 deg, KDL's solution) although both ends are well inside. The check stops at the sample
// where KDL's solution first comes within the margin.
TEST(PathCheck, ElbowFoldedPastItsLimitIsOutOfWorkspace) {
  OSC_PUMA_ONLY();  // its geometry: the elbow, the spherical wrist's closed form, the reach
  Vec6<double> qa, qb;
  qa << 0.2, -0.4, -kPi, 0.3, 0.5, 0.1;
  qb << 0.2, 2.0, -kPi, 0.3, 0.5, 0.1;
  ASSERT_GE(clearance(qa), 0.3);
  ASSERT_GE(clearance(qb), 0.3);
  const MoveCheck<double> r = check_joint_move<double>(qa, qb);
  const int expected = kdl_first_out_of_limits(r.move, qa);
  ASSERT_GT(expected, 0);
  EXPECT_EQ(r.check.status, PathStatus::kOutOfWorkspace);
  EXPECT_EQ(r.check.sample, expected);
  EXPECT_LT(r.check.clearance, params::kWorkspaceMargin);
  EXPECT_LT(r.check.q_end(2), robot::kArm.q_min[2] + params::kWorkspaceMargin);  // joint 3
}

/// q_a, and q_b with joint 5 at q5b: the move turns about joint 5's axis only (the wrist centre
/// stays), so its solution is q5(t) = q5a + (q5b - q5a) psi(t) / |q5b - q5a|, the other joints fixed.
Vec6<double> wrist_q(const MoveCheck<double>& r, const Vec6<double>& qa, double q5b, int i) {
  const double angle = std::abs(q5b - qa(4));
  Vec6<double> q = qa;
  q(4) += (q5b - qa(4)) * (i == N ? 1.0 : r.move.angular().at(r.move.duration() * i / N).p / angle);
  return q;
}

Vec6<double> with_q5(Vec6<double> q, double q5) {
  q(4) = q5;
  return q;
}

const Vec6<double> kWristBase = (Vec6<double>() << 0.2, 0.6, -2.8, 0.4, 0.0, -0.3).finished();

// Joint 5 turned towards its limit (100 deg) and past it: the first sample whose closed-form
// solution lies within the margin.
TEST(PathCheck, WristPastItsLimitIsOutOfWorkspace) {
  OSC_PUMA_ONLY();  // its geometry: the elbow, the spherical wrist's closed form, the reach
  const Vec6<double> qa = with_q5(kWristBase, 1.2);
  const MoveCheck<double> r = check_joint_move<double>(qa, with_q5(qa, 2.0));
  int expected = -1;
  for (int i = 0; i <= N && expected < 0; ++i)
    if (wrist_q(r, qa, 2.0, i)(4) > robot::kArm.q_max[4] - params::kWorkspaceMargin) expected = i;
  ASSERT_GT(expected, 0);
  EXPECT_EQ(r.check.status, PathStatus::kOutOfWorkspace);
  EXPECT_EQ(r.check.sample, expected);
  EXPECT_NEAR(r.check.q_end(4), wrist_q(r, qa, 2.0, expected)(4), 1e-9);
}

// Joint 5 through 0, the wrist singularity: from +0.3 to -0.3 the middle sample is exactly on it
// (rcond 0); from +0.5 to -0.3 it lies between two samples, where no sample's rcond is below the
// threshold (the sign of det J22 changes); from 0.6 to 0.25 the path stays clear of it. Each at the
// first sample where the closed-form solution is below the threshold or past q5 = 0.
TEST(PathCheck, WristSingularityIsNearSingular) {
  OSC_PUMA_ONLY();  // its geometry: the elbow, the spherical wrist's closed form, the reach
  struct Case {
    double q5a, q5b;
    PathStatus status;
  };
  for (const Case& c : {Case{0.3, -0.3, PathStatus::kNearSingular}, Case{0.5, -0.3, PathStatus::kNearSingular},
                        Case{0.6, 0.25, PathStatus::kOk}}) {
    const Vec6<double> qa = with_q5(kWristBase, c.q5a);
    const MoveCheck<double> r = check_joint_move<double>(qa, with_q5(qa, c.q5b));
    const Mat3<double> R_ref = kdl_pose(qa).R;
    int expected = -1;
    double rcond_at_samples = 1;
    for (int i = 0; i <= N && expected < 0; ++i) {
      const Vec6<double> q = wrist_q(r, qa, c.q5b, i);
      rcond_at_samples = std::min(rcond_at_samples, controller_rcond(q, R_ref));
      if (rcond_at_samples < params::kPathMinRcond || q(4) <= 0) expected = i;
    }
    EXPECT_EQ(r.check.status, c.status) << c.q5a;
    EXPECT_EQ(r.check.sample, expected) << c.q5a;
    if (c.q5a == 0.5) {
      EXPECT_GE(rcond_at_samples, params::kPathMinRcond);  // found by the crossing alone
    }
  }
}

// The orientation coordinates' singularity (pitch 90 deg relative to R_ref), where the controller's
// analytic Jacobian is singular: a rotation about the base y axis from a pitch of 60 deg by 40 deg
// fails at the first sample whose rcond (from KDL's solution) is below the threshold.
TEST(PathCheck, OrientationCoordinateSingularityIsNearSingular) {
  const Vec6<double> q0 = test::from_array(robot::kQStart);
  const Pose<double> a = kdl_pose(q0);
  const Mat3<double> R_ref = axis_rotation<double>(Vec3<double>::UnitY(), -60 * kPi / 180) * a.R;
  const Pose<double> b{a.p, axis_rotation<double>(Vec3<double>::UnitY(), 40 * kPi / 180) * a.R};
  const MoveCheck<double> r = check_move<double>(a, b, R_ref, q0);
  int expected = -1;
  Vec6<double> q = q0;
  for (int i = 0; i <= N && expected < 0; ++i) {
    Vec6<double> next;
    ASSERT_TRUE(kdl_ik(sample_pose(r.move, i), q, next));
    q = next;
    if (controller_rcond(q, R_ref) < params::kPathMinRcond) expected = i;
  }
  ASSERT_GT(expected, 0);
  EXPECT_EQ(r.check.status, PathStatus::kNearSingular);
  EXPECT_EQ(r.check.sample, expected);
}

// Samples on either side of that singularity, whose rcond are both above the threshold (pitch 80 and
// 100 deg): the crossing shows in roll and yaw, which turn by pi.
TEST(PathCheck, CoordinateSingularityBetweenSamplesIsNearSingular) {
  const Model<double> model = Model<double>::of(robot::kArm);
  const auto data = std::make_unique<Data<double>>();
  const Vec6<double> q0 = test::from_array(robot::kQStart);
  forward_kinematics(model, *data, q0);
  geometric_jacobian(*data);
  const Mat3<double> R0 = data->R[kDof];
  ArmJacobianFactor<double> Jg;
  Jg.compute(data->J);
  for (double second : {100.0, 80.0}) {
    path_check::SingularityTrace<double> trace;
    PathCheck<double> r;
    EXPECT_FALSE(path_check::near_singular<double>(
        *data, Jg, Mat3<double>(axis_rotation<double>(Vec3<double>::UnitY(), -80 * kPi / 180) * R0), trace, r));
    const Mat3<double> R_ref = axis_rotation<double>(Vec3<double>::UnitY(), -second * kPi / 180) * R0;
    EXPECT_EQ(path_check::near_singular<double>(*data, Jg, R_ref, trace, r), second > 90) << second;
    EXPECT_GE(r.rcond, params::kPathMinRcond);
  }
}

// A target 3 m away, along +x and along -y from the start pose: unreachable at the first sample
// beyond the wrist centre's reach from the shoulder (at the base origin, d1 = 0),
// sqrt((a2 + sqrt(a3^2 + d4^2))^2 + d3^2) = 0.877 m.
TEST(PathCheck, TargetOutOfReachIsUnreachable) {
  OSC_PUMA_ONLY();                    // its geometry: the elbow, the spherical wrist's closed form, the reach
  const auto& L = robot::kArm.links;  // DH rows: a placement's translation is (a, 0, d)
  const double a2 = L[1].placement.p[0], a3 = L[2].placement.p[0], d3 = L[2].placement.p[2], d4 = L[3].placement.p[2];
  const double reach = std::hypot(a2 + std::hypot(a3, d4), d3);
  const Vec6<double> q0 = test::from_array(robot::kQStart);
  const Pose<double> a = kdl_pose(q0);
  for (const Vec3<double>& dir : {Vec3<double>(1, 0, 0), Vec3<double>(0, -1, 0)}) {
    const MoveCheck<double> r = check_move<double>(a, {a.p + 3 * dir, a.R}, a.R, q0);
    int expected = -1;
    for (int i = 0; i <= N && expected < 0; ++i)
      if (sample_pose(r.move, i).p.norm() > reach) expected = i;
    ASSERT_GT(expected, 0);
    EXPECT_EQ(r.check.status, PathStatus::kUnreachable) << dir.transpose();
    EXPECT_EQ(r.check.sample, expected) << dir.transpose();
    EXPECT_GT(r.check.position_error, 0.01);
  }
}

/// float and Q12.19 against double: the same status and failing sample on the moves above, and the
/// end angles of the kOk moves within tol [rad].
template <class S>
void compare_scalar(double tol) {
  Pairs pairs;
  double worst = 0, worst_p = 0, worst_o = 0;
  for (int k = 0; k < kPairs; ++k) {
    Vec6<double> qa, qb;
    pairs.next(qa, qb);
    const MoveCheck<double> d = check_joint_move<double>(qa, qb);
    const MoveCheck<S> s = check_joint_move<S>(qa, qb);
    ASSERT_EQ(s.check.status, PathStatus::kOk) << k;
    worst = std::max(worst, (s.check.q_end.template cast<double>() - d.check.q_end).cwiseAbs().maxCoeff());
    worst_p = std::max(worst_p, static_cast<double>(s.check.position_error));
    worst_o = std::max(worst_o, static_cast<double>(s.check.orientation_error));
  }
  std::printf("end angles vs double %.2e rad; largest residual %.2e m, %.2e rad\n", worst, worst_p, worst_o);
  EXPECT_LE(worst, tol);
  {  // a target out of reach (3 m along x)
    const Vec6<double> q0 = test::from_array(robot::kQStart);
    const Pose<double> a = kdl_pose(q0);
    const MoveCheck<double> d = check_move<double>(a, {a.p + Vec3<double>(3, 0, 0), a.R}, a.R, q0);
    const MoveCheck<S> s = check_move<S>(a, {a.p + Vec3<double>(3, 0, 0), a.R}, a.R, q0);
    EXPECT_EQ(d.check.status, PathStatus::kUnreachable);
    EXPECT_EQ(s.check.status, d.check.status);
    EXPECT_EQ(s.check.sample, d.check.sample);
  }
  if (!test::kPumaBuild) return;  // the pairs below are the PUMA's geometry (its elbow and wrist)
  Vec6<double> fold_a, fold_b;
  fold_a << 0.2, -0.4, -kPi, 0.3, 0.5, 0.1;
  fold_b << 0.2, 2.0, -kPi, 0.3, 0.5, 0.1;
  struct Pair {
    Vec6<double> a, b;
  };
  for (const Pair& p : {Pair{fold_a, fold_b}, Pair{with_q5(kWristBase, 1.2), with_q5(kWristBase, 2.0)},
                        Pair{with_q5(kWristBase, 0.3), with_q5(kWristBase, -0.3)},
                        Pair{with_q5(kWristBase, 0.5), with_q5(kWristBase, -0.3)}}) {
    const MoveCheck<double> d = check_joint_move<double>(p.a, p.b);
    const MoveCheck<S> s = check_joint_move<S>(p.a, p.b);
    EXPECT_EQ(s.check.status, d.check.status) << p.a.transpose();
    EXPECT_EQ(s.check.sample, d.check.sample) << p.a.transpose();
  }
}

TEST(PathCheck, FloatAgreesWithDouble) { compare_scalar<float>(1e-5); }
TEST(PathCheck, FixedAgreesWithDouble) { compare_scalar<Fixed>(2e-4); }

// In fixed point the check's own saturations (near the wrist singularity a determinant's
// reciprocal leaves the range) are discarded, the caller's kept.
TEST(PathCheck, FixedPointKeepsTheCallersFlags) {
  OSC_PUMA_ONLY();  // its geometry: the elbow, the spherical wrist's closed form, the reach
  const Model<Fixed> model = Model<Fixed>::of(robot::kArm);
  const auto data = std::make_unique<Data<Fixed>>();
  // What the check meets next to q5 = 0: the kernels saturate.
  fixed::take_flags();
  forward_kinematics(model, *data, Vec6<Fixed>(with_q5(kWristBase, 2e-4).cast<Fixed>()));
  geometric_jacobian(*data);
  SphericalWristJacobianFactor<Fixed> Jf;
  Jf.compute(data->J);
  EXPECT_NE(fixed::take_flags(), 0u);
  // The move through it, planned first (CartesianMove::plan raises flags of its own in fixed point).
  const Vec6<double> qa = with_q5(kWristBase, 0.3), qb = with_q5(kWristBase, -0.3);
  const Pose<double> a = kdl_pose(qa), b = kdl_pose(qb);
  const auto cast = [](const Pose<double>& p) { return Pose<Fixed>{p.p.cast<Fixed>(), p.R.cast<Fixed>()}; };
  CartesianMove<Fixed> m;
  ASSERT_EQ(m.plan(cast(a), cast(b), CartesianLimits<Fixed>::defaults(), a.R.cast<Fixed>()), ProfileStatus::kOk);
  const Mat3<Fixed> R_ref = a.R.cast<Fixed>();
  const Vec6<Fixed> seed = qa.cast<Fixed>();
  for (const std::uint32_t caller : {0u, std::uint32_t{fixed::kOverflow}}) {
    fixed::take_flags();
    if (caller != 0) {
      volatile double big = 4000;
      EXPECT_EQ(Fixed(big) + Fixed(big), Fixed::max());  // saturates: the caller's own flag
    }
    const PathCheck<Fixed> r = check_path<Fixed>(model, *data, m, R_ref, seed);
    EXPECT_EQ(r.status, PathStatus::kNearSingular);
    EXPECT_EQ(r.sample, N / 2);
    EXPECT_EQ(fixed::take_flags(), caller);
  }
}

}  // namespace
