// The PUMA 560 as an Orocos KDL chain, built from the same parameter table as the kernels
// (osc::robot::kArm.links in osc/puma560.hpp, no numbers repeated here), for independent cross-checks.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>

#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace osc::test {

/// Armature G^2 Jm of joint i (link side), from the parameter table.
inline double armature(int i) {
  const LinkParams& L = robot::kArm.links[i];
  return L.gear_ratio * L.gear_ratio * L.motor_inertia;
}

/// Standard DH: segment i = revolute joint about z of frame i-1, then
/// KDL::Frame::DH(a, alpha, d, 0) = Rz(0) Tz(d) Tx(a) Rx(alpha) to frame i (the joint adds Rz(q_i)).
/// A segment's RigidBodyInertia is expressed in its tip frame, i.e. frame i, as in the reference
/// table; KDL's constructor takes the COG position and the rotational inertia *about the COG*
/// (rigidbodyinertia.hpp), which is what the table gives.
/// The armature is the KDL Joint's inertia parameter. KDL 1.5.1 adds it to the diagonal in
/// ChainDynParam::JntToMass, as armature * qdd_i in ChainIdSolver_RNE, and (through both) in
/// ChainFdSolver_RNE; test_kdl.cpp (KdlConvention) checks this against a chain built with
/// with_armature = false.
inline KDL::Chain puma560_chain(bool with_armature = true) {
  KDL::Chain chain;
  for (int i = 0; i < kDof; ++i) {
    const LinkParams& L = robot::kArm.links[i];
    const KDL::Joint joint(KDL::Joint::RotZ, /*scale=*/1.0, /*offset=*/0.0,
                           /*inertia=*/with_armature ? armature(i) : 0.0);
    const KDL::RigidBodyInertia I(L.mass, KDL::Vector(L.com[0], L.com[1], L.com[2]),
                                  KDL::RotationalInertia(L.inertia[0], L.inertia[1], L.inertia[2], 0, 0, 0));
    chain.addSegment(KDL::Segment(joint, KDL::Frame::DH(L.a, L.alpha, L.d, 0.0), I));
  }
  return chain;
}

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
