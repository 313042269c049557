// Controller, task and friction parameters of the paper's experiment (Section VI): the single
// source of truth for firmware, simulator and tests.
#pragma once

#include "osc/robots/puma560.hpp"

namespace osc::params {

constexpr unsigned kControlHz = 1000;                 ///< control rate: the timer interrupt [Hz]
constexpr double kDt = 1.0 / kControlHz;              ///< sampling time [s]

/// Gains (69), diagonal, one entry per operational axis: x, y, z, then the three rotations.
constexpr double kKnd[6] = {120, 120, 120, 35, 35, 35};
constexpr double kK[6] = {108, 108, 108, 32, 32, 32};
constexpr double kKs[6] = {97, 97, 97, 30, 30, 30};
constexpr double kKi[6] = {2000, 2000, 2000, 3000, 3000, 3000};
constexpr double kKad = 500;      ///< every diagonal entry of K_ad (18x18)
constexpr double kTauDec = 1;     ///< every tau_dec (known Stribeck coefficient) [s^2/rad^2]

/// Trajectory (68): amplitude, angular frequency (period 5 s, f = 1) and envelope rate.
constexpr double kAmplitude = 0.050;            ///< [m]
constexpr double kOmega = 0.4 * puma560::kPi;   ///< [rad/s]
constexpr double kEnvelope = 0.05;              ///< 1 - exp(-kEnvelope t^3)

/// Start pose: the toolbox's qn, with q3 written as -pi so the pose lies inside the WC91 limits.
constexpr double kQStart[6] = {0, puma560::kPi / 4, -puma560::kPi, 0, puma560::kPi / 4, 0};

/// Reciprocal-condition threshold of the Jacobian below which the controller refuses to act.
constexpr double kMinJacobianRcond = 1e-3;

/// Drive electronics. The references give no encoder or amplifier data (puma560.md section 7);
/// these are stated assumptions, used alike by the firmware scaling and the simulated plant.
/// Encoders: 250-line incremental encoders on the motor shafts, read in quadrature (4x).
constexpr double kEncoderCountsPerMotorRev = 1000;
/// DACs: 16-bit bipolar, full scale = the joint torque limit (amplifier in current mode).
constexpr int kDacBits = 16;
constexpr long kDacMaxCode = (1L << (kDacBits - 1)) - 1;  // codes in [-kDacMaxCode, kDacMaxCode]
/// Joint torque limits [N m] at the link (assumed peak amplifier torques).
constexpr double kTorqueLimit[6] = {97.6, 186.4, 89.4, 24.2, 20.1, 21.3};
/// Encoder counts per joint radian: counts per motor rev * |G| / (2 pi).
constexpr double encoder_counts_per_rad(int joint) {
  const double G = puma560::kLinks[joint].gear_ratio;
  return kEncoderCountsPerMotorRev * (G < 0 ? -G : G) / (2 * puma560::kPi);
}

/// Supervision limits.
/// Joint speed above which an encoder change between two ticks is implausible [rad/s] (assumed:
/// about twice the PUMA 560's maximum joint speeds).
constexpr double kMaxJointSpeed[6] = {8.0, 8.0, 8.0, 16.0, 16.0, 16.0};
/// Consecutive ticks a torque may stay clipped at the DAC range before the saturation fault.
constexpr int kSaturationTicks = 50;
/// Sensor-frame timeout of the processor-in-the-loop link [s] (virtual time of the target).
constexpr double kLinkTimeout = 0.1;

/// Friction presets of the simulated plant, model (2): link-side coefficients.
struct FrictionPreset {
  const char* name;
  double vis[6], cou[6], sti[6];
};
/// The paper's Table II (identified on its PUMA 560), tau_dec = 1.
constexpr FrictionPreset kFrictionPaper = {
    "paper", {5.8, 3.7, 6.0, 0.1, 1.9, 0.7}, {4.9, 4.8, 3.0, 1.0, 0.6, 1.2}, {4.1, 4.3, 0.6, 1.5, 0.4, 1.0}};
/// Corke/Armstrong-Helouvry (toolbox) friction referred to the link from the motor-side data in
/// puma560.hpp: viscous B G^2, Coulomb |G| (Tc+ - Tc-) / 2 (the model (2) is symmetric), no Stribeck.
constexpr FrictionPreset corke_friction() {
  FrictionPreset f{"corke", {}, {}, {}};
  for (int i = 0; i < 6; ++i) {
    const double G = puma560::kLinks[i].gear_ratio < 0 ? -puma560::kLinks[i].gear_ratio : puma560::kLinks[i].gear_ratio;
    f.vis[i] = puma560::kMotorViscous[i] * G * G;
    f.cou[i] = G * (puma560::kMotorCoulombPos[i] - puma560::kMotorCoulombNeg[i]) / 2;
    f.sti[i] = 0;
  }
  return f;
}
constexpr FrictionPreset kFrictionCorke = corke_friction();
constexpr FrictionPreset kFrictionNone = {"none", {0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 0}};

}  // namespace osc::params
