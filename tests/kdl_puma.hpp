// The PUMA 560 as an Orocos KDL chain, built from the same parameter table as the kernels
// (osc/puma560.hpp), for independent cross-checks.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>

#include "osc/model.hpp"

namespace osc::test {

/// Standard DH: segment i = joint about z of frame i-1, then Rz(0) Tz(d) Tx(a) Rx(alpha) to frame i.
/// KDL expresses a segment's inertia in its tip frame, i.e. frame i, as the reference table does.
/// The armature G^2 Jm is the joint's rotor inertia (added to A(q) by KDL's ChainDynParam).
inline KDL::Chain puma560_chain() {
  KDL::Chain chain;
  for (const puma560::LinkParams& L : puma560::kLinks) {
    const double armature = L.gear_ratio * L.gear_ratio * L.motor_inertia;
    const KDL::Joint joint(KDL::Joint::RotZ, 1.0, 0.0, armature);
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

}  // namespace osc::test
