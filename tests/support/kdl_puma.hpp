// An arm's table as an Orocos KDL chain, built from the same parameter table as the kernels
// (osc::robot::kArm for the built robot, no numbers repeated here), for independent cross-checks.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>

#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace osc::test {

/// Armature G^2 Jm of a link's joint (link side).
inline double armature(const LinkParams& L) { return L.gear_ratio * L.gear_ratio * L.motor_inertia; }
/// The built robot's, of joint i.
inline double armature(int i) { return armature(robot::kArm.links[i]); }

/// A placement (osc/robots/arm.hpp) as a KDL frame.
inline KDL::Frame kdl_frame(const Placement& P) {
  return KDL::Frame(
      KDL::Rotation(P.R[0][0], P.R[0][1], P.R[0][2], P.R[1][0], P.R[1][1], P.R[1][2], P.R[2][0], P.R[2][1], P.R[2][2]),
      KDL::Vector(P.p[0], P.p[1], P.p[2]));
}

/// An arm's table as a KDL chain: a fixed segment to frame 0 (the base placement, where it is not the
/// identity: then the chain has 7 segments, the first fixed), then segment i =
/// revolute joint about z of frame i-1 followed by the placement P_i to frame i (the joint adds
/// Rz(q_i); for a DH row P_i = KDL::Frame::DH(a, alpha, d, 0) = Tz(d) Tx(a) Rx(alpha)).
/// A segment's RigidBodyInertia is expressed in its tip frame, i.e. frame i, as in the reference
/// table; KDL's constructor takes the COG position and the rotational inertia *about the COG*
/// (rigidbodyinertia.hpp), which is what the table gives.
/// The armature is the KDL Joint's inertia parameter. KDL 1.5.1 adds it to the diagonal in
/// ChainDynParam::JntToMass, as armature * qdd_i in ChainIdSolver_RNE, and (through both) in
/// ChainFdSolver_RNE; test_kdl.cpp (KdlConvention) checks this against a chain built with
/// with_armature = false.
/// With `payload`, link 6's segment carries it too: KDL's own sum of the two rigid-body inertias in frame 6
/// (RigidBodyInertia's operator+), not the firmware's combine_bodies.
inline KDL::Chain arm_chain(const ArmDescription& arm, bool with_armature = true, const Payload* payload = nullptr) {
  KDL::Chain chain;
  const KDL::Frame base = kdl_frame(arm.base);
  if (!KDL::Equal(base, KDL::Frame::Identity(), 1e-15))
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None), base));
  for (int i = 0; i < kDof; ++i) {
    const LinkParams& L = arm.links[i];
    const KDL::Joint joint(KDL::Joint::RotZ, /*scale=*/1.0, /*offset=*/0.0,
                           /*inertia=*/with_armature ? armature(L) : 0.0);
    const double* I = L.inertia;
    KDL::RigidBodyInertia inertia(L.mass, KDL::Vector(L.com[0], L.com[1], L.com[2]),
                                  KDL::RotationalInertia(I[0], I[1], I[2], I[3], I[4], I[5]));
    if (payload && i == kDof - 1) {
      const double* P = payload->inertia;
      inertia =
          inertia + KDL::RigidBodyInertia(payload->mass, KDL::Vector(payload->com[0], payload->com[1], payload->com[2]),
                                          KDL::RotationalInertia(P[0], P[1], P[2], P[3], P[4], P[5]));
    }
    chain.addSegment(KDL::Segment(joint, kdl_frame(L.placement), inertia));
  }
  return chain;
}

/// The built robot's chain.
inline KDL::Chain puma560_chain(bool with_armature = true) { return arm_chain(robot::kArm, with_armature); }

inline KDL::JntArray to_kdl(const Vec6<double>& v) {
  KDL::JntArray a(kDof);
  for (int i = 0; i < kDof; ++i) a(i) = v(i);
  return a;
}

inline Vec6<double> from_kdl(const KDL::JntArray& a) {
  Vec6<double> v;
  for (int i = 0; i < kDof; ++i) v(i) = a(i);
  return v;
}

inline Vec6<double> from_kdl(const KDL::Twist& t) {
  Vec6<double> v;
  v << t.vel.x(), t.vel.y(), t.vel.z(), t.rot.x(), t.rot.y(), t.rot.z();
  return v;
}

}  // namespace osc::test
