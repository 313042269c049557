// The robot description format: what a 6-joint revolute arm is to the firmware.
// A robot is one constant table in this format (firmware/robots/<arm>/), and the build selects
// one (osc/robot.hpp, CMake OSC_ROBOT); nothing above this layer names a particular arm.
//
// The chain: frame 0 is placed in the base frame by ArmDescription::base; joint i turns about the z
// axis of frame i-1, and link i's frame is F_i = F_{i-1} Rz(q_i) P_i, with P_i its constant
// placement. Standard DH is the case P_i = Tz(d) Tx(a) Rx(alpha) (dh_placement); a URDF's joint
// origins, axes and tool offset are the general case (tools/armgen writes them in this form).
#pragma once

namespace osc {

/// Joints of every arm the kernels handle (fixed-size matrices throughout).
constexpr int kDof = 6;
constexpr double kPi = 3.14159265358979323846;

/// A constant rigid transform: a frame's axes R (columns, row-major here) and origin p [m] in its
/// parent frame, x_parent = R x + p.
struct Placement {
  double R[3][3];
  double p[3];
};
constexpr Placement kIdentityPlacement = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 0, 0}};

/// Not defined: a table that reaches it does not compile (not a constant expression).
void alpha_is_not_a_quarter_turn();

/// cos and sin of a quarter turn k pi/2, exact (the twists a DH table uses for perpendicular and
/// parallel axes). Any other angle is not a constant expression here: a table of general angles is
/// written as matrices (the generator's output), not through dh_placement.
constexpr void quarter_turn(double alpha, double& c, double& s) {
  constexpr double kTol = 1e-12;
  const double k = alpha / (kPi / 2);
  const long n = k < 0 ? -static_cast<long>(-k + 0.5) : static_cast<long>(k + 0.5);
  if (k - static_cast<double>(n) > kTol || static_cast<double>(n) - k > kTol) alpha_is_not_a_quarter_turn();
  const int m = static_cast<int>(((n % 4) + 4) % 4);
  c = m == 0 ? 1.0 : (m == 2 ? -1.0 : 0.0);
  s = m == 1 ? 1.0 : (m == 3 ? -1.0 : 0.0);
}

/// The standard DH placement Tz(d) Tx(a) Rx(alpha) (alpha a multiple of pi/2).
constexpr Placement dh_placement(double a, double d, double alpha) {
  double c = 0, s = 0;
  quarter_turn(alpha, c, s);
  return {{{1, 0, 0}, {0, c, -s}, {0, s, c}}, {a, 0, d}};
}

/// Inertial and drive data of one link.
struct LinkParams {
  Placement placement;   // P_i: frame i in joint i's turned frame F_{i-1} Rz(q_i)
  double mass;           // [kg]
  double com[3];         // COM in frame i [m]
  double inertia[6];     // about the COM, axes of frame i: Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m^2]
  double motor_inertia;  // Jm [kg m^2], motor side
  double gear_ratio;     // G (signed), motor turns per joint turn
};

/// The arm: kinematics, inertia, gravity and joint limits.
struct ArmDescription {
  const char* name;
  Placement base;  ///< frame 0 in the base frame
  LinkParams links[kDof];
  double gravity;      ///< magnitude [m/s^2]; gravity acts along -z of the base frame
  double q_min[kDof];  ///< joint limits [rad]
  double q_max[kDof];
};

/// The drive electronics: encoders on the motor shafts, a bipolar DAC per joint commanding torque
/// (amplifier in current mode), and the speeds beyond which an encoder change is implausible.
struct DriveParams {
  double encoder_counts_per_motor_rev;  ///< after quadrature decoding
  int dac_bits;                         ///< bipolar: codes in [-(2^(bits-1) - 1), 2^(bits-1) - 1]
  double torque_limit[kDof];            ///< joint torque at full-scale DAC code [N m]
  double max_joint_speed[kDof];         ///< [rad/s]
};

/// One off-diagonal term of a coupling matrix C: joint `row`'s angle gains `c` times motor channel
/// `col`'s (row > col: C is unit lower triangular).
struct CouplingTerm {
  int row, col;
  double c;  ///< [rad/rad]
};
constexpr int kMaxCouplingTerms = 6;

/// How the motor encoders read the joints. Channel i counts its motor's shaft angle; referred to
/// the joint through the motor's gears it is e_i = counts_i / counts_per_rad[i]. The joint angles
/// are q = q_start + C e, C unit lower triangular (its off-diagonal terms listed; none: each
/// encoder reads its own joint). Joint torques reach the motors through the transpose: the
/// channels' torques, referred to the joints, are tau_m = C^T tau (the same power, tau^T qd).
struct EncoderMap {
  const char* name;
  double counts_per_rad[kDof];  ///< counts per radian of the motor angle referred to its joint
  int coupling_terms;
  CouplingTerm coupling[kMaxCouplingTerms];
};

/// A map's coupling matrix C (unit lower triangular, from its terms) and C^-1, by forward
/// substitution (C X = I column by column, rows top down).
constexpr void coupling_matrices(const EncoderMap& map, double (&C)[kDof][kDof], double (&inverse)[kDof][kDof]) {
  for (int i = 0; i < kDof; ++i)
    for (int j = 0; j < kDof; ++j) C[i][j] = i == j ? 1.0 : 0.0;
  for (int k = 0; k < map.coupling_terms; ++k) C[map.coupling[k].row][map.coupling[k].col] += map.coupling[k].c;
  for (int j = 0; j < kDof; ++j)
    for (int i = 0; i < kDof; ++i) {
      double x = i == j ? 1.0 : 0.0;
      for (int k = 0; k < i; ++k) x -= C[i][k] * inverse[k][j];
      inverse[i][j] = x;
    }
}

/// Encoders of one resolution on every motor shaft, each reading its own joint.
constexpr EncoderMap uniform_encoders(const char* name, const ArmDescription& arm, double counts_per_motor_rev) {
  EncoderMap m{name, {}, 0, {}};
  for (int i = 0; i < kDof; ++i) {
    const double G = arm.links[i].gear_ratio < 0 ? -arm.links[i].gear_ratio : arm.links[i].gear_ratio;
    m.counts_per_rad[i] = counts_per_motor_rev * G / (2 * kPi);
  }
  return m;
}

/// A set of motor inertias [kg m^2], motor side.
struct MotorInertias {
  const char* name;
  double jm[kDof];
};

/// The drive train of a real arm, as published (or estimated, where its table says so): the
/// motors, the encoders on their shafts, the amplifiers' limits, a potentiometer on every joint,
/// an index pulse once per motor revolution.
struct DriveTrain {
  EncoderMap encoders;                  ///< the arm's own encoders and coupling
  MotorInertias motor_inertia_alt;      ///< a second published set (the first: ArmDescription's links)
  double torque_constant[kDof];         ///< K_m [N m / A]
  double motor_torque_limit[kDof];      ///< the amplifier's current limit times K_m [N m], motor side
  int pot_bits;                         ///< the potentiometers' ADC: codes 0 .. 2^bits - 1
  double pot_min[kDof], pot_max[kDof];  ///< joint angle at code 0 and at full scale [rad]
  double index_angle[kDof];  ///< the motor shaft's angle at its index pulse [rad, 0..2 pi), from its angle at q = 0
};

/// A pose an operator can declare the arm to stand at (declare_pose): its name, its joint angles.
struct NamedPose {
  const char* name;
  double q[kDof];  ///< [rad]
  const char* doc;
};

/// Joint friction of model (2), link side: viscous, Coulomb and Stribeck coefficients.
struct FrictionCoefficients {
  const char* name;
  double vis[kDof], cou[kDof], sti[kDof];
};
constexpr FrictionCoefficients kFrictionNone = {"none", {0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0}};

constexpr double abs_of(double v) { return v < 0 ? -v : v; }

/// What a model-based monitor may assume about the arm it runs on: bounds on how far the arm can
/// differ from its model, each the robot description's statement (docs/safety.md derives the
/// residual monitor's thresholds from them).
struct ModelErrorBounds {
  double link_inertia;  ///< every link's inertial parameters (mass, first and second moments), relative
  double amp_gain;      ///< an amplifier's gain error, relative to the torque commanded
  double amp_offset;    ///< an amplifier's offset, relative to its channel's full-scale torque
  double ripple;        ///< torque ripple, relative to the torque commanded
  double amp_lag;       ///< an amplifier's current loop, its first-order time constant at most [s]
  double encoder_edge;  ///< an encoder edge's distance from its nominal place at most [counts]
  FrictionCoefficients friction_lo, friction_hi;  ///< the band the arm's friction lies in, drift included
};

/// The band of friction coefficients that covers every preset in `presets` (each coefficient's
/// smallest and largest), widened by a relative drift: [min (1 - drift), max (1 + drift)].
template <int N>
constexpr void friction_band(const FrictionCoefficients* const (&presets)[N], double drift, FrictionCoefficients& lo,
                             FrictionCoefficients& hi) {
  for (int i = 0; i < kDof; ++i) {
    double v[3][2] = {{1e300, 0}, {1e300, 0}, {1e300, 0}};  // per coefficient: min, max
    for (const FrictionCoefficients* p : presets) {
      const double c[3] = {p->vis[i], p->cou[i], p->sti[i]};
      for (int k = 0; k < 3; ++k) {
        if (c[k] < v[k][0]) v[k][0] = c[k];
        if (c[k] > v[k][1]) v[k][1] = c[k];
      }
    }
    lo.vis[i] = v[0][0] * (1 - drift), hi.vis[i] = v[0][1] * (1 + drift);
    lo.cou[i] = v[1][0] * (1 - drift), hi.cou[i] = v[1][1] * (1 + drift);
    lo.sti[i] = v[2][0] * (1 - drift), hi.sti[i] = v[2][1] * (1 + drift);
  }
}

/// Largest DAC code magnitude.
constexpr long dac_max_code(const DriveParams& drives) { return (1L << (drives.dac_bits - 1)) - 1; }

/// True when the last three joint axes meet at the frame-6 origin (a spherical wrist with the
/// operational point at its centre): link 4's origin lies on joint 4's axis (P_4's translation along
/// z only) and links 5 and 6 add no translation. Then o4 = o5 = o6 lies on the axes of joints 4-6,
/// the linear rows of the Jacobian do not depend on joints 4-6, and J is block lower-triangular
/// (kernels/opspace.hpp). In DH terms: a4 = a5 = a6 = 0 and d5 = d6 = 0.
constexpr bool has_spherical_wrist(const ArmDescription& arm) {
  const double* p4 = arm.links[3].placement.p;
  const double* p5 = arm.links[4].placement.p;
  const double* p6 = arm.links[5].placement.p;
  return p4[0] == 0 && p4[1] == 0 && p5[0] == 0 && p5[1] == 0 && p5[2] == 0 && p6[0] == 0 && p6[1] == 0 &&
         p6[2] == 0;
}

/// True when the rotation of a placement is a permutation of the axes with signs (every entry 0 or
/// +-1): the DH twists 0 and +-pi/2, and a URDF's quarter-turn rpy. The kernels then place a frame
/// by moving columns, without a product.
constexpr bool is_signed_permutation(const Placement& P) {
  for (int r = 0; r < 3; ++r) {
    int nonzero = 0;
    for (int c = 0; c < 3; ++c) {
      const double v = P.R[r][c];
      if (v != 0 && v != 1 && v != -1) return false;
      nonzero += v != 0;
    }
    if (nonzero != 1) return false;
  }
  return true;
}

}  // namespace osc
