// A URDF read straight into an Orocos KDL chain (urdfdom's parser, then KDL segments), for the
// independent check of a generated arm table: this reader shares no code with tools/armgen, which
// turns the same URDF into the firmware's placements (osc/robots/arm.hpp). The URDF's own frames
// are kept: each segment is the joint's origin, then its rotation about its axis, and carries the
// child link's inertial in the child's frame.
#pragma once

#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/rigidbodyinertia.hpp>
#include <stdexcept>
#include <string>
#include <urdf_parser/urdf_parser.h>

namespace osc::test {

inline KDL::Frame kdl_pose(const urdf::Pose& p) {
  double x, y, z, w;
  p.rotation.getQuaternion(x, y, z, w);
  return KDL::Frame(KDL::Rotation::Quaternion(x, y, z, w), KDL::Vector(p.position.x, p.position.y, p.position.z));
}

/// A link's inertial in its own frame: KDL takes the COM and the rotational inertia about the COM
/// (in the link's axes), so the URDF's inertial frame C is turned into the link's: I_L = R_C I_C R_C^T.
inline KDL::RigidBodyInertia kdl_inertia(const urdf::LinkConstSharedPtr& link) {
  if (!link->inertial) return KDL::RigidBodyInertia::Zero();
  const urdf::Inertial& in = *link->inertial;
  const KDL::Frame C = kdl_pose(in.origin);
  const KDL::RotationalInertia Ic(in.ixx, in.iyy, in.izz, in.ixy, in.ixz, in.iyz);
  // KDL's RigidBodyInertia rotated by C.M: the same mass and COM, its inertia about the COM in new axes.
  const KDL::RigidBodyInertia about_com = C.M * KDL::RigidBodyInertia(in.mass, KDL::Vector::Zero(), Ic);
  return KDL::RigidBodyInertia(in.mass, C.p, KDL::RotationalInertia(about_com.getRotationalInertia()));
}

/// The chain of `urdf_path` from its root link to `tip_link`: fixed joints become fixed segments,
/// revolute and continuous joints rotational ones about their axes (other joints are refused).
inline KDL::Chain kdl_chain_from_urdf(const std::string& urdf_path, const std::string& tip_link) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(urdf_path);
  if (!model) throw std::runtime_error("kdl_chain_from_urdf: cannot parse " + urdf_path);
  // The joints from the tip up to the root, then the segments root first.
  std::vector<urdf::JointConstSharedPtr> joints;
  for (urdf::LinkConstSharedPtr l = model->getLink(tip_link); l && l->parent_joint; l = l->getParent())
    joints.insert(joints.begin(), l->parent_joint);
  if (joints.empty()) throw std::runtime_error("kdl_chain_from_urdf: no link " + tip_link);
  KDL::Chain chain;
  for (const urdf::JointConstSharedPtr& j : joints) {
    const KDL::Frame O = kdl_pose(j->parent_to_joint_origin_transform);
    const KDL::RigidBodyInertia I = kdl_inertia(model->getLink(j->child_link_name));
    if (j->type == urdf::Joint::FIXED) {
      chain.addSegment(KDL::Segment(j->child_link_name, KDL::Joint(j->name, KDL::Joint::None), O, I));
    } else if (j->type == urdf::Joint::REVOLUTE || j->type == urdf::Joint::CONTINUOUS) {
      const KDL::Vector axis = O.M * KDL::Vector(j->axis.x, j->axis.y, j->axis.z);
      chain.addSegment(KDL::Segment(j->child_link_name, KDL::Joint(j->name, O.p, axis, KDL::Joint::RotAxis), O, I));
    } else {
      throw std::runtime_error("kdl_chain_from_urdf: joint " + j->name + " is neither fixed nor revolute");
    }
  }
  return chain;
}

}  // namespace osc::test
