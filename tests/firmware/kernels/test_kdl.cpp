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
#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>

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

/// Running maximum of the relative error of one quantity.
struct Worst {
  const char* name;
  double value = 0;
  void add(double err, double ref_norm, double floor) { value = std::max(value, err / std::max(ref_norm, floor)); }
  void report() const { std::printf("max relative error vs KDL, %-30s %.2e\n", name, value); }
};

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
  const KDL::Wrenches f_ext(with.getNrOfSegments(), KDL::Wrench::Zero());  // the base's fixed segment too
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
  const KDL::Chain chain = test::puma560_chain();
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  KDL::ChainDynParam dyn(chain, kGravityVec);
  KDL::ChainJntToJacDotSolver jacdot(chain);
  jacdot.setRepresentation(KDL::ChainJntToJacDotSolver::HYBRID);  // ref point frame-6 origin, base axes

  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  test::RandomStates rs;
  Worst w_fk{"FK, all link frames [R p]"}, w_jac{"geometric Jacobian"}, w_A{"A(q) with armature"}, w_c{"c(q, qd)"},
      w_g{"g(q)"}, w_jd{"Jdot qd (HYBRID)"};
  KDL::Jacobian J(kDof);
  KDL::JntSpaceInertiaMatrix H(kDof);
  KDL::JntArray C(kDof), G(kDof);
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0);
    const KDL::JntArray kq = to_kdl(q), kqd = to_kdl(qd);
    Vec6<double> c, g, jdqd;
    {
      test::NoMalloc guard;
      forward_kinematics(model, data, q);
      geometric_jacobian(data);
      joint_inertia(model, data);
      const VelocityProducts<double> vp = velocity_products(model, data, qd);
      c = vp.c;
      jdqd = vp.jdot_qd;
      g = gravity_torques(model, data);
    }
    // Every link frame: KDL's frame after segment i + 1 is our frame i (segment 1: the base placement).
    for (int i = 1; i <= kDof; ++i) {
      KDL::Frame F;
      ASSERT_GE(fk.JntToCart(kq, F, i + 1), 0);
      Eigen::Matrix<double, 3, 4> ours, ref;
      ours << data.R[i], data.o[i];
      for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) ref(r, s) = F.M(r, s);
        ref(r, 3) = F.p(r);
      }
      w_fk.add((ours - ref).norm(), ref.norm(), 0.0);
    }
    ASSERT_GE(jac.JntToJac(kq, J), 0);
    w_jac.add((J.data - data.J).norm(), J.data.norm(), 0.0);
    ASSERT_GE(dyn.JntToMass(kq, H), 0);
    ASSERT_GE(dyn.JntToCoriolis(kq, kqd, C), 0);
    ASSERT_GE(dyn.JntToGravity(kq, G), 0);
    w_A.add((H.data - data.A).norm(), H.data.norm(), 0.0);
    w_c.add((C.data - c).norm(), C.data.norm(), kFloor);
    w_g.add((G.data - g).norm(), G.data.norm(), kFloor);
    KDL::Twist t;
    ASSERT_GE(jacdot.JntToJacDot(KDL::JntArrayVel(kq, kqd), t), 0);
    const Vec6<double> kjd = from_kdl(t);
    w_jd.add((kjd - jdqd).norm(), kjd.norm(), kFloor);
  }
  for (const Worst* w : {&w_fk, &w_jac, &w_A, &w_c, &w_g, &w_jd}) {
    w->report();
    EXPECT_LE(w->value, kTol) << w->name;
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

}  // namespace
