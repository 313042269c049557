// PUMA 560: the single source of truth for firmware, simulator and tests.
// Source: ../shared/reference/puma560.md (Corke & Armstrong-Helouvry consensus values,
// standard DH, d1 = 0, armature G^2*Jm referred to the link side); friction from the paper's
// Table II; drive electronics as stated assumptions.
#pragma once

#include "osc/robots/arm.hpp"

namespace osc::puma560 {

constexpr ArmDescription kArm = {
    "PUMA 560",
    {
        {0.0, 0.0, kPi / 2, 0.0, {0, 0, 0}, {0, 0.35, 0}, 200e-6, -62.6111},
        {0.4318, 0.0, 0.0, 17.4, {-0.3638, 0.006, 0.2275}, {0.13, 0.524, 0.539}, 200e-6, 107.815},
        {0.0203, 0.15005, -kPi / 2, 4.8, {-0.0203, -0.0141, 0.070}, {0.066, 0.086, 0.0125}, 200e-6, -53.7063},
        {0.0, 0.4318, kPi / 2, 0.82, {0, 0.019, 0}, {1.8e-3, 1.3e-3, 1.8e-3}, 33e-6, 76.0364},
        {0.0, 0.0, -kPi / 2, 0.34, {0, 0, 0}, {0.3e-3, 0.4e-3, 0.3e-3}, 33e-6, 71.923},
        {0.0, 0.0, 0.0, 0.09, {0, 0, 0.032}, {0.15e-3, 0.15e-3, 0.04e-3}, 33e-6, 76.686},
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

/// Drive electronics. The references give no encoder or amplifier data (puma560.md section 7);
/// these are stated assumptions, used alike by the firmware scaling and the simulated plant.
/// Encoders: 250-line incremental encoders on the motor shafts, read in quadrature (4x).
/// DACs: 16-bit bipolar, full scale = the joint torque limit (assumed peak amplifier torques).
/// Plausible joint speeds: about twice the PUMA 560's maximum joint speeds.
constexpr DriveParams kDrives = {1000, 16, {97.6, 186.4, 89.4, 24.2, 20.1, 21.3}, {8.0, 8.0, 8.0, 16.0, 16.0, 16.0}};

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

}  // namespace osc::puma560
