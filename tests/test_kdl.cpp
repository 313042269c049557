// Kernels and plant against Orocos KDL, an independent dynamics library, on 1000 random
// non-singular states. Relative error = |ours - KDL| / max(|KDL|, floor), floor 1e-3 of the
// quantity's typical size (stated per check).
#include <gtest/gtest.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>

#include "kdl_puma.hpp"
#include "osc/dynamics.hpp"
#include "plant.hpp"
#include "test_util.hpp"

using namespace osc;
using osc::test::to_kdl;

namespace {

constexpr int kStates = 1000;
constexpr double kTol = 1e-9;

struct Worst {
  const char* name;
  double value = 0;
  ~Worst() { std::printf("max relative error vs KDL, %-28s %.2e\n", name, value); }
  void add(double err, double ref, double floor) { value = std::max(value, err / std::max(ref, floor)); }
};

TEST(Kdl, KinematicsDynamicsAndPlantAgreeOnRandomStates) {
  const KDL::Chain chain = test::puma560_chain();
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainJntToJacSolver jac(chain);
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -puma560::kGravity));
  KDL::ChainJntToJacDotSolver jacdot(chain);
  jacdot.setRepresentation(KDL::ChainJntToJacDotSolver::HYBRID);
  KDL::ChainFdSolver_RNE fd(chain, KDL::Vector(0, 0, -puma560::kGravity));

  const Model<double> model = Model<double>::puma560();
  Data<double> data;
  sim::ArticulatedBody body;
  test::RandomStates rs;
  Worst w_fk{"FK, all link frames"}, w_jac{"geometric Jacobian"}, w_A{"A(q) with armature"},
      w_c{"c(q, qd)"}, w_g{"g(q)"}, w_jd{"Jdot qd"}, w_fd{"plant forward dynamics"};
  for (int k = 0; k < kStates; ++k) {
    const Vec6<double> q = rs.q_nonsingular(), qd = rs.vec(2.0), tau = rs.vec(40.0);
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
    // Forward kinematics of every link frame (positions in m, rotations).
    for (int i = 1; i <= kDof; ++i) {
      KDL::Frame F;
      ASSERT_GE(fk.JntToCart(kq, F, i), 0);
      double e = 0;
      for (int r = 0; r < 3; ++r) {
        e = std::max(e, std::abs(F.p(r) - data.o[i](r)));
        for (int s = 0; s < 3; ++s) e = std::max(e, std::abs(F.M(r, s) - data.R[i](r, s)));
      }
      w_fk.add(e, 1.0, 1.0);  // rotations are unit-size, positions ~1 m
    }
    // Geometric Jacobian at the frame-6 origin, base frame.
    KDL::Jacobian J(kDof);
    ASSERT_GE(jac.JntToJac(kq, J), 0);
    w_jac.add((J.data - data.J).norm(), J.data.norm(), 1.0);
    // Mass matrix, Coriolis/centrifugal torques, gravity.
    KDL::JntSpaceInertiaMatrix H(kDof);
    KDL::JntArray C(kDof), G(kDof);
    ASSERT_GE(dyn.JntToMass(kq, H), 0);
    ASSERT_GE(dyn.JntToCoriolis(kq, kqd, C), 0);
    ASSERT_GE(dyn.JntToGravity(kq, G), 0);
    w_A.add((H.data - data.A).norm(), H.data.norm(), 1.0);
    w_c.add((C.data - c).norm(), C.data.norm(), 1e-3);
    w_g.add((G.data - g).norm(), G.data.norm(), 1e-3);
    // Jdot qd (hybrid: reference point at the end effector, base axes).
    KDL::Twist t;
    ASSERT_GE(jacdot.JntToJacDot(KDL::JntArrayVel(kq, kqd), t), 0);
    Vec6<double> kjd;
    kjd << t.vel.x(), t.vel.y(), t.vel.z(), t.rot.x(), t.rot.y(), t.rot.z();
    w_jd.add((kjd - jdqd).norm(), kjd.norm(), 1e-3);
    // The simulator's articulated-body forward dynamics against KDL's forward dynamics.
    KDL::JntArray kqdd(kDof);
    KDL::Wrenches f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero());
    ASSERT_GE(fd.CartToJnt(kq, kqd, to_kdl(tau), f_ext, kqdd), 0);
    const Vec6<double> qdd = body.forward_dynamics(q, qd, tau);
    w_fd.add((kqdd.data - qdd).norm(), kqdd.data.norm(), 1e-3);
  }
  EXPECT_LT(w_fk.value, kTol);
  EXPECT_LT(w_jac.value, kTol);
  EXPECT_LT(w_A.value, kTol);
  EXPECT_LT(w_c.value, kTol);
  EXPECT_LT(w_g.value, kTol);
  EXPECT_LT(w_jd.value, kTol);
  EXPECT_LT(w_fd.value, kTol);
}

}  // namespace
