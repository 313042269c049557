// tools/armgen: an arm's URDF and drive sheet (YAML) to the firmware's constant table
// (osc/robots/<arm>.hpp, the format of firmware/robots/include/osc/robots/arm.hpp). docs/arms.md.
#pragma once

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace armgen {

/// A description the generator refuses: a stable name (the tests match it) and what, where.
/// The program prints `armgen: error: <name>: <what>` and exits 2.
struct Error : std::runtime_error {
  std::string name;
  Error(std::string n, const std::string& what) : std::runtime_error(what), name(std::move(n)) {}
};

/// A number of the sheet: its value and its C++ text. The sheet may write a number as an
/// arithmetic expression of numbers and `pi` (+ - * / and parentheses); the header carries the
/// expression (pi as kPi, each number with 15 significant digits), so the compiler computes it
/// exactly as the generator's checks did.
struct Value {
  double v = 0;
  std::string text = "0";
  bool simple = true;    ///< one number or pi, without an operator
  bool integer = false;  ///< an integer literal in C++ (its text has no '.' or exponent)
};
using Six = std::array<Value, 6>;

/// `src` as a Value; `where` names it in an error (sheet_value, not_finite).
Value parse_value(const std::string& src, const std::string& where);
/// `text` as a double literal when it is an integer literal ("12" -> "12.0"), else unchanged.
std::string as_double(const std::string& text);
/// A double as the header prints it: 15 significant digits, no negative zero.
std::string number(double v);
/// An angle as the header prints it: d * kPi / 180 when within 1e-12 rad of a whole number d of
/// degrees, else number().
std::string angle(double v);

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// A rigid placement: x_parent = R x + p.
struct Frame {
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
};
/// a b, its rotation and translation snapped (snap_rotation, snap_translation).
Frame compose(const Frame& a, const Frame& b);
Frame inverse(const Frame& a);
/// Entries within 1e-12 of 0 or +-1 become exactly that.
Mat3 snap_rotation(const Mat3& R);
/// Entries within 1e-15 of 0 become 0.
Vec3 snap_translation(const Vec3& p);
/// R = Rz(yaw) Ry(pitch) Rx(roll), snapped.
Mat3 rpy_rotation(double roll, double pitch, double yaw);

/// Mass, centre of mass and inertia about it (frame axes) of a body.
struct Inertial {
  double mass = 0;
  Vec3 com = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
};

/// The source or the reasoning of a group of the sheet (at least one of them).
struct Text {
  std::string source, estimate;
};

struct MotorSet {
  std::string name;
  Six jm;
  Text text;
};
struct Coupling {
  int joint, motor;  ///< 1-based: q_joint gains c e_motor
  Value c;
};
struct FrictionPreset {
  std::string name;
  bool motor = false;  ///< motor side {viscous, coulomb_pos, coulomb_neg}, else link side {vis, cou, sti}
  Six a, b, c;
  Text text;
};
struct Pose {
  std::string name, doc, symbol;
  Six q;
};

/// The drive sheet: what the URDF lacks, each group with its source or estimate.
struct Sheet {
  std::string path, arm, name, urdf, about;
  Text kinematics, joint_limits;
  std::map<std::string, Text> inertial_exceptions;  ///< link name -> why its inertial is no body
  Value gravity;
  Text gravity_text;
  Six gear;
  Text gear_text;
  std::vector<MotorSet> motor_sets;  ///< the first is the model's (kArm)
  Text motor_text;
  int motor_alt = 0;  ///< index of kDriveTrain.motor_inertia_alt
  Value model_cpr;    ///< the model's uniform encoders, counts per motor revolution
  Text model_encoder_text;
  std::string encoder_name;
  bool absolute = false;
  std::string encoder_unit;  ///< rad_per_count | counts_per_motor_rev | counts_per_joint_rev
  Six encoder;
  std::vector<Coupling> coupling;
  Text encoder_text;
  int dac_bits = 0;
  Six dac_full_scale;
  Text dac_text;
  Six torque_constant;
  Text torque_constant_text;
  Six motor_torque_limit;
  Text motor_torque_limit_text;
  Six joint_speed;
  Text joint_speed_text;
  bool pots = false;
  int pot_bits = 0;
  Six pot_min, pot_max;
  Text pot_text;
  bool index = false;
  Six index_angle;
  Text index_text;
  bool current = false;  ///< a current monitor on every amplifier
  int current_bits = 0;
  Value current_range, current_gain, current_offset, current_noise;
  Text current_text;
  std::vector<FrictionPreset> friction;
  Value link_inertia, amp_gain, amp_offset, ripple, amp_lag, encoder_edge, drift;
  std::vector<std::string> band;  ///< the friction band's presets
  Text bounds_text;
  Pose start;
  Text start_text;
  std::vector<Pose> named;  ///< after the start pose
  Text named_text;
  std::vector<Pose> reference;
  Text reference_text;
  std::string op_frame;  ///< empty: the last moving link
  std::array<Value, 3> op_xyz, op_rpy;
  Text op_text;
  Value cart_velocity, cart_acceleration, cart_jerk;
  Text cart_text;
  Value payload_mass, payload_com_reach, payload_inertia;  ///< the rated payload and its envelope
  Text payload_text;
};

/// Reads and checks the sheet (errors sheet_*, not_finite, sheet_no_source).
Sheet read_sheet(const std::string& path);

/// One moving joint of the chain.
struct Joint {
  std::string name, child;
  Vec3 axis;
  double lower = 0, upper = 0;
  bool continuous = false;
};

/// The chain in the table's terms: F_j = F_{j-1} Rz(q_j) P_j, F_0 = base.
struct Chain {
  std::string root;
  std::array<Joint, 6> joints;
  Frame base;
  std::array<Frame, 6> placement;
  std::array<Inertial, 6> link;  ///< in frame F_j: COM, inertia about it in F_j's axes
  Frame tool;                    ///< the operational point in the last moving link's URDF frame
  std::string tool_frame;        ///< the link it is given from
};

/// Reads the URDF and converts it (errors urdf_parse, chain_joints, mimic_joint, joint_type,
/// missing_inertial, mass_not_positive, inertia_not_positive_definite, not_finite, limits_inverted,
/// zero_axis, operational_frame).
Chain read_chain(const std::string& urdf_path, const Sheet& sheet);

/// The description's cross checks: named poses within the limits (pose_outside_limits), coupling
/// indices, and the fixed-point range of every quantity the firmware holds in Q12.19
/// (fixed_point_range, fixed_point_resolution).
void check_description(const Sheet& sheet, const Chain& chain);

/// The header's text. `sheet_name` and `urdf_name`: the descriptions' paths as the banner shows them.
std::string emit_header(const Sheet& sheet, const Chain& chain, const std::string& sheet_name,
                        const std::string& urdf_name);

}  // namespace armgen
