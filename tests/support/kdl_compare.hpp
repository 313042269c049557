// The kernels on an arm's table against a KDL chain of the same arm, state by state: frames, J, A(q),
// c(q, qd), g(q) and Jdot qd, each as its running worst relative error (test_kdl.cpp,
// test_arm_descriptions.cpp).
//
// Error measure, per state and quantity: rel = ||ours - KDL|| / max(||KDL||, floor), Frobenius /
// Euclidean norms, SI units. Floors: none for the frames [R p] and J (their norms are >= sqrt 3: the
// rotation, the unit joint axes), none for A (>= the armature); `floor` for c, g and Jdot qd (a state
// where the reference nearly vanishes is measured absolutely).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <string>

#include "osc/kernels/dynamics.hpp"
#include "test_util.hpp"

namespace osc::test {

/// Running maximum of the relative error of one quantity.
struct Worst {
  std::string name;
  double value = 0;
  void add(double err, double ref_norm, double floor) { value = std::max(value, err / std::max(ref_norm, floor)); }
  void report(const char* prefix = "") const {
    std::printf("%smax relative error vs KDL, %-30s %.2e\n", prefix, name.c_str(), value);
  }
};

class KdlComparison {
 public:
  /// `first_frame`..kDof: our frames compared, frame i with KDL's after segment i + `segment_offset`.
  /// `armature_in_chain`: the chain's joints carry the armature (else it is added to KDL's A(q)).
  KdlComparison(const KDL::Chain& chain, double gravity, int first_frame, int segment_offset, bool armature_in_chain,
                double floor, const std::string& prefix = "")
      : chain_(chain),
        fk_(chain_),
        jac_(chain_),
        dyn_(chain_, KDL::Vector(0, 0, -gravity)),
        jacdot_(chain_),
        first_(first_frame),
        offset_(segment_offset),
        armature_in_chain_(armature_in_chain),
        floor_(floor),
        w_{{prefix + "FK [R p]"},
           {prefix + "geometric Jacobian"},
           {prefix + "A(q) with armature"},
           {prefix + "c(q, qd)"},
           {prefix + "g(q)"},
           {prefix + "Jdot qd (HYBRID)"}} {
    jacdot_.setRepresentation(KDL::ChainJntToJacDotSolver::HYBRID);  // ref point frame-6 origin, base axes
  }

  /// The kernels at (q, qd) on `model` against the chain.
  void add(const Model<double>& model, Data<double>& data, const Vec6<double>& q, const Vec6<double>& qd) {
    VelocityProducts<double> vp;
    Vec6<double> g;
    {
      NoMalloc guard;
      forward_kinematics(model, data, q);
      geometric_jacobian(data);
      joint_inertia(model, data);
      vp = velocity_products(model, data, qd);
      g = gravity_torques(model, data);
    }
    KDL::JntArray kq(kDof), kqd(kDof);
    for (int i = 0; i < kDof; ++i) kq(i) = q(i), kqd(i) = qd(i);
    for (int i = first_; i <= kDof; ++i) {
      KDL::Frame F;
      ASSERT_GE(fk_.JntToCart(kq, F, i + offset_), 0);
      Eigen::Matrix<double, 3, 4> ours, ref;
      ours << data.R[i], data.o[i];
      for (int r = 0; r < 3; ++r) {
        for (int s = 0; s < 3; ++s) ref(r, s) = F.M(r, s);
        ref(r, 3) = F.p(r);
      }
      w_[0].add((ours - ref).norm(), ref.norm(), 0.0);
    }
    KDL::Jacobian J(kDof);
    KDL::JntSpaceInertiaMatrix H(kDof);
    KDL::JntArray C(kDof), G(kDof);
    ASSERT_GE(jac_.JntToJac(kq, J), 0);
    w_[1].add((J.data - data.J).norm(), J.data.norm(), 0.0);
    ASSERT_GE(dyn_.JntToMass(kq, H), 0);
    ASSERT_GE(dyn_.JntToCoriolis(kq, kqd, C), 0);
    ASSERT_GE(dyn_.JntToGravity(kq, G), 0);
    // A URDF has no motors: then the table's armature G^2 Jm is added to KDL's link inertia.
    const Mat6<double> A_ref = armature_in_chain_ ? H.data : H.data + Mat6<double>(model.armature.asDiagonal());
    w_[2].add((A_ref - data.A).norm(), A_ref.norm(), 0.0);
    w_[3].add((C.data - vp.c).norm(), C.data.norm(), floor_);
    w_[4].add((G.data - g).norm(), G.data.norm(), floor_);
    KDL::Twist t;
    ASSERT_GE(jacdot_.JntToJacDot(KDL::JntArrayVel(kq, kqd), t), 0);
    Vec6<double> jd;
    jd << t.vel.x(), t.vel.y(), t.vel.z(), t.rot.x(), t.rot.y(), t.rot.z();
    w_[5].add((jd - vp.jdot_qd).norm(), jd.norm(), floor_);
  }

  /// The worst relative error so far of quantity k (0 frames, 1 J, 2 A, 3 c, 4 g, 5 Jdot qd).
  double worst(int k) const { return w_[k].value; }

  /// Prints every quantity's worst and expects each within `tol`.
  void expect_within(double tol) const {
    for (const Worst& w : w_) {
      w.report();
      EXPECT_LE(w.value, tol) << w.name;
    }
  }

 private:
  KDL::Chain chain_;
  KDL::ChainFkSolverPos_recursive fk_;
  KDL::ChainJntToJacSolver jac_;
  KDL::ChainDynParam dyn_;
  KDL::ChainJntToJacDotSolver jacdot_;
  int first_, offset_;
  bool armature_in_chain_;
  double floor_;
  Worst w_[6];
};

}  // namespace osc::test
