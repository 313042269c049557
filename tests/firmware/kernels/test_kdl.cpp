// Kernels and plant against Orocos KDL 1.5.1, an independent kinematics/dynamics library, on random
// non-singular states (deterministic seed, test::RandomStates).
//
// Error measure, per state and quantity: rel = ||ours - KDL|| / max(||KDL||, floor), Frobenius /
// Euclidean norms, SI units. Floors: FK frame [R p] and J need none (their norms are >= sqrt 3: the
// rotation, the unit joint axes); A none (>= the armature); c, g, Jdot qd and the plant's q_dd use
// 1e-3 (N m, m/s^2 or rad/s^2), below every norm met on these states, so never active (||c|| 0.025-15
// N m for |qd_i| <= 2 rad/s, ||g|| 2.6-47 N m, ||Jdot qd|| 0.28-18). Tolerance: rel <= 1e-9.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <random>
#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "kdl_compare.hpp"
#include "kdl_puma.hpp"
#include "osc/kernels/dynamics.hpp"
#include "plant.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;

namespace {

constexpr int kStates = 1000;       // kinematics and dynamics kernels
constexpr int kPlantStates = 1000;  // plant forward dynamics (>= 500 asked)
constexpr double kTol = 1e-9;
constexpr double kFloor = 1e-3;

const KDL::Vector kGravityVec(0, 0, -robot::kArm.gravity);

using test::Worst;

Mat6<double> to_eigen(const KDL::JntSpaceInertiaMatrix& H) { return H.data; }

// KDL's treatment of the Joint inertia parameter (the armature), checked empirically rather than
// assumed: a chain built without it must differ by exactly diag(armature) in JntToMass and by
// armature * qdd in inverse dynamics, and ChainFdSolver_RNE must solve with the armature included.
TEST(KdlConvention, JointInertiaIsTheArmatureInMassMatrixIdAndFd) {
  const KDL::Chain with = test::puma560_chain(true), without = test::puma560_chain(false);
  KDL::ChainDynParam dyn_w(with, kGravityVec), dyn_wo(without, kGravityVec);
  KDL::ChainIdSolver_RNE id_w(with, kGravityVec), id_wo(without, kGravityVec);
  KDL::ChainFdSolver_RNE fd_w(with, kGravityVec);
  Vec6<double> arm;
  for (int i = 0; i < kDof; ++i) arm(i) = test::armature(i);
  ASSERT_GT(arm.minCoeff(), 0.1);  // so that a missing armature could not hide in round-off
  test::RandomStates rs;
  const KDL::Wrenches f_ext(with.getNrOfSegments(), KDL::Wrench::Zero());
  for (int k = 0; k < 50; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), qdd = rs.vec(5.0), tau = rs.vec(40.0);
    KDL::JntSpaceInertiaMatrix Hw(kDof), Hwo(kDof);
    ASSERT_GE(dyn_w.JntToMass(to_kdl(q), Hw), 0);
    ASSERT_GE(dyn_wo.JntToMass(to_kdl(q), Hwo), 0);
    const Mat6<double> dH = to_eigen(Hw) - to_eigen(Hwo);
    EXPECT_LT((dH - Mat6<double>(arm.asDiagonal())).norm(), 1e-12);

    KDL::JntArray tw(kDof), two(kDof);
    ASSERT_GE(id_w.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(qdd), f_ext, tw), 0);
    ASSERT_GE(id_wo.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(qdd), f_ext, two), 0);
    EXPECT_LT((from_kdl(tw) - from_kdl(two) - arm.cwiseProduct(qdd)).norm(), 1e-11);

    KDL::JntArray C(kDof), G(kDof), kqdd(kDof);
    ASSERT_GE(dyn_w.JntToCoriolis(to_kdl(q), to_kdl(qd), C), 0);
    ASSERT_GE(dyn_w.JntToGravity(to_kdl(q), G), 0);
    ASSERT_GE(fd_w.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(tau), f_ext, kqdd), 0);
    const Vec6<double> ref = Eigen::LLT<Mat6<double>>(to_eigen(Hw)).solve(tau - from_kdl(C) - from_kdl(G));
    EXPECT_LT((from_kdl(kqdd) - ref).norm(), 1e-10 * std::max(ref.norm(), kFloor));
  }
}

TEST(Kdl, KinematicsAndDynamicsKernelsAgreeOnRandomStates) {
  OSC_PUMA_ONLY();
  // Every link frame: KDL's frame after segment i is our frame i (the PUMA's base placement is the
  // identity: no base segment, test::arm_chain).
  const KDL::Chain chain = test::puma560_chain();
  ASSERT_EQ(chain.getNrOfSegments(), static_cast<unsigned>(kDof));
  test::KdlComparison cmp(chain, robot::kArm.gravity, 1, 0, true, kFloor);
  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  test::RandomStates rs;
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0);
    cmp.add(model, data, q, qd);
  }
  cmp.expect_within(kTol);
}

/// A random 6R arm in the general form: a base placement, link placements with arbitrary rotations
/// and translations (no DH structure: no permutation, no planar offset), full inertia tensors (a box's
/// principal moments turned by a random rotation: positive definite, triangle inequality held).
/// With `quarter_turns`, every placement's rotation is a random signed permutation (a URDF's quarter
/// turns: the kernels' permutation path) instead.
ArmDescription random_general_arm(std::mt19937_64& rng, bool quarter_turns) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.2, 1.0);
  const auto rotation = [&] {
    if (!quarter_turns)
      return Eigen::AngleAxisd(kPi * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng);
    for (int c = 0; c < 3; ++c) R(perm[c], c) = u(rng) < 0 ? -1.0 : 1.0;
    if (R.determinant() < 0) R.col(2) = -R.col(2);  // a rotation, not a reflection
    return R;
  };
  const auto placement = [&](double reach) {
    Placement P{};
    const Eigen::Matrix3d R = rotation();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) P.R[r][c] = R(r, c);
      P.p[r] = reach * u(rng);
    }
    return P;
  };
  ArmDescription arm{"random", placement(0.2), {}, 9.81, {}, {}};
  for (LinkParams& L : arm.links) {
    L.placement = placement(0.4);
    L.mass = 5 * pos(rng);
    for (double& c : L.com) c = 0.2 * u(rng);
    const Eigen::Vector3d box(0.3 * pos(rng), 0.3 * pos(rng), 0.3 * pos(rng));  // edge lengths [m]
    const Eigen::Vector3d b2 = box.cwiseProduct(box);
    const Eigen::Matrix3d R = rotation();
    const Eigen::Matrix3d I =
        R * (L.mass / 12 * Eigen::Vector3d(b2(1) + b2(2), b2(0) + b2(2), b2(0) + b2(1))).asDiagonal() * R.transpose();
    const double in[6] = {I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)};
    for (int k = 0; k < 6; ++k) L.inertia[k] = in[k];
    L.motor_inertia = 2e-5 * pos(rng);
    L.gear_ratio = 100 * u(rng);
  }
  return arm;
}

// The kernels' general paths (a base placement, rotations that are not permutations or are any signed
// permutation, offsets off the DH plane, products of inertia), which the PUMA's table never takes,
// against KDL on random arms.
TEST(Kdl, GeneralArmsKernelsAgreeOnRandomStates) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  test::Worst worst[6] = {{"general arms: FK [R p]"}, {"general arms: J"},    {"general arms: A(q)"},
                          {"general arms: c(q, qd)"}, {"general arms: g(q)"}, {"general arms: Jdot qd"}};
  for (int a = 0; a < 40; ++a) {
    const bool quarter_turns = a % 2 == 1;
    const ArmDescription arm = random_general_arm(rng, quarter_turns);
    const Model<double> model = Model<double>::of(arm);
    ASSERT_FALSE(model.base_identity);
    for (const auto& l : model.link) {
      if (quarter_turns)
        ASSERT_NE(l.form.rotation, Rotation::kGeneral);
      else
        ASSERT_EQ(l.form.rotation, Rotation::kGeneral);
      ASSERT_FALSE(l.form.planar);
      ASSERT_TRUE(quarter_turns || !l.diagonal);  // a box turned by quarter turns stays diagonal
    }
    const KDL::Chain chain = test::arm_chain(arm);
    ASSERT_EQ(chain.getNrOfSegments(), static_cast<unsigned>(kDof + 1));  // the base segment first
    // Frame i (0..6) is KDL's after segment i + 1.
    test::KdlComparison one(chain, arm.gravity, 0, 1, true, kFloor);
    Data<double> data;
    for (int k = 0; k < 50; ++k) {
      Vec6<double> q, qd;
      for (int i = 0; i < kDof; ++i) q(i) = kPi * u(rng), qd(i) = 2 * u(rng);
      one.add(model, data, q, qd);
    }
    for (int w = 0; w < 6; ++w) worst[w].value = std::max(worst[w].value, one.worst(w));
  }
  for (const test::Worst& w : worst) {
    w.report();
    EXPECT_LE(w.value, kTol) << w.name;
  }
}

TEST(Kdl, PlantForwardDynamicsAgreesWithChainFdSolverRne) {
  const KDL::Chain chain = test::puma560_chain();
  KDL::ChainFdSolver_RNE fd(chain, kGravityVec);
  const sim::ArticulatedBody body;
  test::RandomStates rs;
  rs.rng.seed(777);  // states independent of the kinematics test
  const KDL::Wrenches f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero());
  KDL::JntArray kqdd(kDof);
  Worst w_fd{"plant forward dynamics q_dd"};
  for (int k = 0; k < kPlantStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), tau = rs.vec(40.0);
    ASSERT_GE(fd.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(tau), f_ext, kqdd), 0);
    const Vec6<double> qdd = body.forward_dynamics(q, qd, tau);
    w_fd.add((kqdd.data - qdd).norm(), kqdd.data.norm(), kFloor);
  }
  w_fd.report();
  EXPECT_LE(w_fd.value, kTol);
}

/// Payloads at the flange as issue 57 tests them (0.5, 1.5, 2.5 kg up to 0.1 m off the flange), the last
/// with an inertia that has products (a box turned about two axes).
std::vector<Payload> test_payloads() {
  Payload a, b, c;
  a.mass = 0.5, a.com[2] = 0.1;
  b.mass = 1.5, b.com[0] = 0.1, b.com[2] = 0.05;
  const double in_b[6] = {2e-3, 3e-3, 4e-3, 0, 0, 0};
  std::copy(in_b, in_b + 6, b.inertia);
  c.mass = 2.5, c.com[0] = 0.05, c.com[1] = -0.07, c.com[2] = 0.1;
  const double in_c[6] = {0.012, 0.010, 0.008, 1.5e-3, -1e-3, 0.5e-3};
  std::copy(in_c, in_c + 6, c.inertia);
  return {a, b, c};
}

// A payload in the model (Model::of's link 6 with combine_bodies) against KDL's chain whose last segment
// carries it by KDL's own rigid-body sum: FK, J, A, c, g and J-dot qd on random states.
TEST(Kdl, APayloadOnLinkSixAgreesWithKdl) {
  OSC_PUMA_ONLY();
  for (const Payload& p : test_payloads()) {
    const KDL::Chain chain = test::arm_chain(robot::kArm, true, &p);
    test::KdlComparison cmp(chain, robot::kArm.gravity, 1, 0, true, kFloor);
    const Model<double> model = Model<double>::of(robot::kArm, 0.0, p);
    Data<double> data;
    test::RandomStates rs;
    for (int k = 0; k < 200; ++k) cmp.add(model, data, rs.q_nonsingular(), rs.vec(2.0));
    cmp.expect_within(kTol);
  }
}

// The same payloads without the model: the gravity torque they add is what they weigh (a check that the
// comparison above could fail: a 0.5 kg payload changes g by newton-metres).
TEST(Kdl, APayloadChangesTheGravityTorqueByItsWeight) {
  OSC_PUMA_ONLY();
  const Model<double> bare = Model<double>::of(robot::kArm);
  for (const Payload& p : test_payloads()) {
    const Model<double> loaded = Model<double>::of(robot::kArm, 0.0, p);
    Data<double> d0, d1;
    const Vec6<double> q = joint_vector<double>(robot::kQStart);
    forward_kinematics(bare, d0, q);
    forward_kinematics(loaded, d1, q);
    // Static: the payload's weight at its centre of mass, -J_c^T m g_vec, g_vec along -z.
    const Vec3<double> c = d1.o[kDof] + d1.R[kDof] * Vec3<double>(p.com[0], p.com[1], p.com[2]);
    Vec6<double> expect;
    for (int j = 0; j < kDof; ++j) {
      const Vec3<double> z = d1.R[j].col(2);
      expect(j) = z.cross(c - d1.o[j]).z() * p.mass * robot::kArm.gravity;
    }
    const Vec6<double> delta = gravity_torques(loaded, d1) - gravity_torques(bare, d0);
    EXPECT_LT((delta - expect).norm(), 1e-9 * std::max(1.0, expect.norm())) << p.mass << " kg";
    EXPECT_GT(expect.norm(), 0.4 * p.mass) << "the pose must load the payload's weight";
  }
}

TEST(Kdl, PlantWithAPayloadAgreesWithChainFdSolverRne) {
  OSC_PUMA_ONLY();
  for (const Payload& p : test_payloads()) {
    const KDL::Chain chain = test::arm_chain(robot::kArm, true, &p);
    KDL::ChainFdSolver_RNE fd(chain, kGravityVec);
    const sim::ArticulatedBody body(1.0, p);
    test::RandomStates rs;
    rs.rng.seed(778);
    const KDL::Wrenches f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero());
    KDL::JntArray kqdd(kDof);
    Worst w{"plant forward dynamics q_dd with a payload"};
    for (int k = 0; k < 200; ++k) {
      const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), tau = rs.vec(40.0);
      ASSERT_GE(fd.CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(tau), f_ext, kqdd), 0);
      w.add((kqdd.data - body.forward_dynamics(q, qd, tau)).norm(), kqdd.data.norm(), kFloor);
    }
    w.report();
    EXPECT_LE(w.value, kTol);
  }
}

}  // namespace
