// The build's arm (CMake OSC_ROBOT) as an Orocos KDL chain read from its own description, not through the
// generator (tools/armgen): the drive sheet (yaml-cpp) names the URDF and the operational point's link, and
// urdfdom reads the URDF into the chain (kdl_urdf.hpp). The chain's last segment is the firmware's frame 6
// (test_arm_descriptions checks that for every arm over 1 000 states).
#pragma once

#include <yaml-cpp/yaml.h>

#include <kdl/chain.hpp>
#include <stdexcept>
#include <string>
#include <urdf_parser/urdf_parser.h>

#include "kdl_urdf.hpp"

namespace osc::test {

/// The child link of the sixth moving joint from the URDF's root: a chain's last moving link (the
/// operational point's link when the sheet names none).
inline std::string sixth_moving_link(const std::string& urdf_path) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(urdf_path);
  if (!model) throw std::runtime_error("sixth_moving_link: cannot parse " + urdf_path);
  int moving = 0;
  for (urdf::LinkConstSharedPtr l = model->getRoot(); l && l->child_joints.size() == 1;) {
    const urdf::JointConstSharedPtr& j = l->child_joints.front();
    if (j->type != urdf::Joint::FIXED && ++moving == 6) return j->child_link_name;
    l = model->getLink(j->child_link_name);
  }
  throw std::runtime_error("sixth_moving_link: " + urdf_path + " has no chain of six moving joints from its root");
}

/// The KDL chain of the arm whose drive sheet is `sheet_path` (firmware/robots/<arm>/<arm>.yaml), from its
/// URDF's root to the operational point's link (the sheet's operational_point.frame, else the last moving link).
inline KDL::Chain urdf_arm_chain(const std::string& sheet_path) {
  const YAML::Node sheet = YAML::LoadFile(sheet_path);
  const std::string dir = sheet_path.substr(0, sheet_path.find_last_of('/') + 1);
  const std::string urdf = dir + sheet["urdf"].as<std::string>();
  const YAML::Node frame = sheet["operational_point"]["frame"];
  return kdl_chain_from_urdf(urdf, frame ? frame.as<std::string>() : sixth_moving_link(urdf));
}

}  // namespace osc::test
