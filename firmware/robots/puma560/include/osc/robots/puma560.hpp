// PUMA 560: the single source of truth for firmware, simulator and tests.
// Source: ../shared/reference/puma560.md (Corke & Armstrong-Helouvry consensus values,
// standard DH, d1 = 0, armature G^2*Jm referred to the link side); friction from the paper's
// Table II; drive electronics as stated assumptions.
#pragma once

#include <string_view>

#include "osc/robots/arm.hpp"

namespace osc::puma560 {

/// Motor inertias [kg m^2]: the toolbox's (Corke/Armstrong-Helouvry consensus, RTB `mdl_puma560`),
/// the model's own (kArm), and AKB86's (RTB `mdl_puma560akb`): +45 / +105 / +50 % on J1-J3.
inline constexpr MotorInertias kMotorInertiaToolbox = {"toolbox", {200e-6, 200e-6, 200e-6, 33e-6, 33e-6, 33e-6}};
inline constexpr MotorInertias kMotorInertiaAkb86 = {"akb86", {291e-6, 409e-6, 299e-6, 35e-6, 35e-6, 35e-6}};

constexpr ArmDescription kArm = {
    "PUMA 560",
    kIdentityPlacement,
    {
        {dh_placement(0.0, 0.0, kPi / 2), 0.0, {0, 0, 0}, {0, 0.35, 0, 0, 0, 0}, kMotorInertiaToolbox.jm[0], -62.6111},
        {dh_placement(0.4318, 0.0, 0.0),
         17.4,
         {-0.3638, 0.006, 0.2275},
         {0.13, 0.524, 0.539, 0, 0, 0},
         kMotorInertiaToolbox.jm[1],
         107.815},
        {dh_placement(0.0203, 0.15005, -kPi / 2),
         4.8,
         {-0.0203, -0.0141, 0.070},
         {0.066, 0.086, 0.0125, 0, 0, 0},
         kMotorInertiaToolbox.jm[2],
         -53.7063},
        {dh_placement(0.0, 0.4318, kPi / 2),
         0.82,
         {0, 0.019, 0},
         {1.8e-3, 1.3e-3, 1.8e-3, 0, 0, 0},
         kMotorInertiaToolbox.jm[3],
         76.0364},
        {dh_placement(0.0, 0.0, -kPi / 2),
         0.34,
         {0, 0, 0},
         {0.3e-3, 0.4e-3, 0.3e-3, 0, 0, 0},
         kMotorInertiaToolbox.jm[4],
         71.923},
        {dh_placement(0.0, 0.0, 0.0), 0.09, {0, 0, 0.032}, {0.15e-3, 0.15e-3, 0.04e-3, 0, 0, 0}, kMotorInertiaToolbox.jm[5], 76.686},
    },
    9.81,
    // Joint limits (WC91 set, as in the MATLAB toolbox model).
    {-160 * kPi / 180, -45 * kPi / 180, -225 * kPi / 180, -110 * kPi / 180, -100 * kPi / 180, -266 * kPi / 180},
    {160 * kPi / 180, 225 * kPi / 180, 45 * kPi / 180, 170 * kPi / 180, 100 * kPi / 180, 266 * kPi / 180},
};
static_assert(has_spherical_wrist(kArm), "the PUMA's wrist axes meet at the frame-6 origin");

/// Named poses [rad].
constexpr double kQz[kDof] = {0, 0, 0, 0, 0, 0};
constexpr double kQr[kDof] = {0, kPi / 2, -kPi / 2, 0, 0, 0};
constexpr double kQs[kDof] = {0, 0, -kPi / 2, 0, 0, 0};
constexpr double kQn[kDof] = {0, kPi / 4, kPi, 0, kPi / 4, 0};
/// Start pose of the task: the toolbox's qn, with q3 written as -pi so it lies inside the limits.
constexpr double kQStart[kDof] = {0, kPi / 4, -kPi, 0, kPi / 4, 0};
/// The poses an operator may declare (declare_pose), in code order. Each within the joint limits.
constexpr NamedPose kNamedPoses[] = {
    {"start", {0, kPi / 4, -kPi, 0, kPi / 4, 0}, "the task's start pose (kQStart): the paper's experiment starts here"},
    {"zero", {0, 0, 0, 0, 0, 0}, "every joint at zero (the toolbox's qz): the arm stretched out horizontally"},
    {"ready", {0, kPi / 2, -kPi / 2, 0, 0, 0}, "the toolbox's qr: the arm straight up"},
    {"stretch", {0, 0, -kPi / 2, 0, 0, 0}, "the toolbox's qs: the upper arm horizontal, the forearm up"},
};
constexpr int kNamedPoseCount = sizeof(kNamedPoses) / sizeof(*kNamedPoses);
/// The code of the named pose `name` (its index in kNamedPoses), or -1.
constexpr int named_pose_code(std::string_view name) {
  for (int i = 0; i < kNamedPoseCount; ++i)
    if (name == kNamedPoses[i].name) return i;
  return -1;
}
constexpr bool named_poses_valid() {
  for (const NamedPose& p : kNamedPoses)
    for (int i = 0; i < kDof; ++i)
      if (p.q[i] < kArm.q_min[i] || p.q[i] > kArm.q_max[i]) return false;
  for (int i = 0; i < kDof; ++i)
    if (kNamedPoses[0].q[i] != kQStart[i]) return false;
  return kNamedPoseCount <= 255;
}
static_assert(named_poses_valid(),
              "each named pose within the joint limits, the first the start pose, codes in a byte");

/// Drive electronics. The references give no encoder or amplifier data (puma560.md section 7);
/// these are stated assumptions, used alike by the firmware scaling and the simulated plant.
/// Encoders: 250-line incremental encoders on the motor shafts, read in quadrature (4x).
/// DACs: 16-bit bipolar, full scale = the joint torque limit (assumed peak amplifier torques).
/// Plausible joint speeds: about twice the PUMA 560's maximum joint speeds.
constexpr DriveParams kDrives = {1000, 16, {97.6, 186.4, 89.4, 24.2, 20.1, 21.3}, {8.0, 8.0, 8.0, 16.0, 16.0, 16.0}};

/// The encoders of the model's drives (kDrives): 1000 counts per motor revolution on every joint,
/// each encoder reading its own joint. The default of the firmware and of the `ideal` plant.
constexpr EncoderMap kEncodersUniform = uniform_encoders("uniform", kArm, kDrives.encoder_counts_per_motor_rev);

/// The PUMA 560's own drive train (../shared/reference/puma560.md section 9; sources per field).
constexpr DriveTrain kDriveTrain = {
    // Encoders: the Trident PUMA interface code (ROBOT.C v4.3, Mark III boards), its joint scales
    // [rad/count] 1.0035e-4, 7.3156e-5, 1.17e-4, 8.2663e-5, 8.7376e-5, 8.1885e-5: 1000 counts per
    // motor revolution on J1 and J3-J6, about 797 on J2. Wrist coupling: its wristCouplingG,
    // q5 = e5 - 0.0139037 e4, q6 = e6 + 0.0130401 e4 - 0.180556 e5.
    {"trident",
     {1 / 1.0035e-4, 1 / 7.3156e-5, 1 / 1.17e-4, 1 / 8.2663e-5, 1 / 8.7376e-5, 1 / 8.1885e-5},
     3,
     {{4, 3, -0.0139037}, {5, 3, 0.0130401}, {5, 4, -0.180556}}},
    kMotorInertiaAkb86,
    // K_m: 0.228 N m/A on J2 (Corke, RVC3). J1 and J3: estimated the same (the same motor inertia,
    // 200e-6, in the toolbox: the same motor). J4-J6: not found; estimated from the wrist motors'
    // torque limit below over the same full-scale current, 0.9 / 0.228 = 3.95 A.
    {0.228, 0.228, 0.228, 24.2 / 76.0364 / (0.9 / 0.228), 20.1 / 71.923 / (0.9 / 0.228), 21.3 / 76.686 / (0.9 / 0.228)},
    // Motor torque limit: 0.9 N m on J2 (Corke, RVC3), about 97 N m at the joint. J1 and J3:
    // estimated the same (the same motor). J4-J6: not found; estimated as the DAC full-scale joint
    // torques over |G| (AKB86's 24.2 / 20.1 / 21.3 N m), so that the wrist's amplifiers limit where its
    // DACs do.
    {0.9, 0.9, 0.9, 24.2 / 76.0364, 20.1 / 71.923, 21.3 / 76.686},
    // Potentiometers: one per joint, read by a 12-bit ADC (Trident ROBOT.C, options POT, POT6).
    // Their span is not found: estimated as the joint's travel (the WC91 limits) plus 10 degrees at
    // each end.
    12,
    {-170 * kPi / 180, -55 * kPi / 180, -235 * kPi / 180, -120 * kPi / 180, -110 * kPi / 180, -276 * kPi / 180},
    {170 * kPi / 180, 235 * kPi / 180, 55 * kPi / 180, 180 * kPi / 180, 110 * kPi / 180, 276 * kPi / 180},
    // Index pulses: one per motor revolution (Trident ROBOT.H, INDEX6). Where on the shaft is not
    // found, and differs from arm to arm: estimated, spread over the turn so that no test relies on
    // one place.
    {0.7, 2.1, 4.0, 1.3, 5.5, 3.1},
};
static_assert(kDriveTrain.encoders.coupling_terms <= kMaxCouplingTerms);

/// Toolbox (Corke/Armstrong-Helouvry) motor-side friction: viscous B and Coulomb Tc(+), Tc(-).
constexpr double kMotorViscous[kDof] = {1.48e-3, 0.817e-3, 1.38e-3, 71.2e-6, 82.6e-6, 36.7e-6};
constexpr double kMotorCoulombPos[kDof] = {0.395, 0.126, 0.132, 11.2e-3, 9.26e-3, 3.96e-3};
constexpr double kMotorCoulombNeg[kDof] = {-0.435, -0.071, -0.105, -16.9e-3, -14.5e-3, -10.5e-3};

/// Friction presets of the simulated plant, model (2), link side.
/// The paper's Table II (identified on its PUMA 560), tau_dec = 1.
constexpr FrictionCoefficients kFrictionPaper = {
    "paper", {5.8, 3.7, 6.0, 0.1, 1.9, 0.7}, {4.9, 4.8, 3.0, 1.0, 0.6, 1.2}, {4.1, 4.3, 0.6, 1.5, 0.4, 1.0}};
/// Corke/Armstrong-Helouvry (toolbox) friction referred to the link from the motor-side data:
/// viscous B G^2, Coulomb |G| (Tc+ - Tc-) / 2 (the model (2) is symmetric), no Stribeck.
constexpr FrictionCoefficients corke_friction() {
  FrictionCoefficients f{"corke", {}, {}, {}};
  for (int i = 0; i < kDof; ++i) {
    const double G = abs_of(kArm.links[i].gear_ratio);
    f.vis[i] = kMotorViscous[i] * G * G;
    f.cou[i] = G * (kMotorCoulombPos[i] - kMotorCoulombNeg[i]) / 2;
    f.sti[i] = 0;
  }
  return f;
}
constexpr FrictionCoefficients kFrictionCorke = corke_friction();
/// Every preset, for command lines and tests.
constexpr const FrictionCoefficients* kFrictionPresets[] = {&kFrictionPaper, &kFrictionCorke, &kFrictionNone};

/// The model's error bounds on a PUMA 560 (docs/safety.md, "The residual monitor"):
/// - link inertia +-10 %: the spread of the published PUMA link parameters around the consensus
///   values (../shared/reference/puma560.md);
/// - amplifiers: gain within +-2 %, offset within 0.2 % of full scale, ripple within 3 % (estimates,
///   twice the realistic plant's mid values: docs/experiment.md), a current loop of at most 0.5 ms
///   (the top of the range the realistic plant's estimate states);
/// - encoders: each edge within 0.2 counts of its nominal place (an estimate, twice the realistic
///   plant's +-0.1: quadrature phase and line errors), so consecutive edges lie 0.6-1.4 counts apart;
/// - friction: between the paper's Table II and the Corke/Armstrong-Helouvry values, coefficient by
///   coefficient, with +-30 % drift with temperature. (The motor inertias' two published sets are
///   the drive train's, kDriveTrain.motor_inertia_alt.)
constexpr ModelErrorBounds model_error_bounds() {
  ModelErrorBounds b{0.10, 0.02, 0.002, 0.03, 0.5e-3, 0.2, {"band_lo", {}, {}, {}}, {"band_hi", {}, {}, {}}};
  const FrictionCoefficients* const measured[] = {&kFrictionPaper, &kFrictionCorke};
  friction_band(measured, 0.30, b.friction_lo, b.friction_hi);
  return b;
}
constexpr ModelErrorBounds kModelErrorBounds = model_error_bounds();

}  // namespace osc::puma560
