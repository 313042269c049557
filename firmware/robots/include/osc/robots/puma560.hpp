// PUMA 560 parameters: the single source of truth for firmware, simulator and tests.
// Source: ../shared/reference/puma560.md (Corke & Armstrong-Helouvry consensus values,
// standard DH, d1 = 0, armature G^2*Jm referred to the link side).
#pragma once

namespace osc::puma560 {

constexpr int kDof = 6;
constexpr double kPi = 3.14159265358979323846;

/// Standard DH row and inertial data of one link (inertia about the COM, axes of frame i).
struct LinkParams {
  double a, d, alpha;        // [m], [m], [rad]
  double mass;               // [kg]
  double com[3];             // COM in frame i [m]
  double inertia[3];         // Ixx, Iyy, Izz about the COM [kg m^2]; products are 0
  double motor_inertia;      // Jm [kg m^2], motor side
  double gear_ratio;         // G (signed), motor turns per joint turn
};

constexpr LinkParams kLinks[kDof] = {
    {0.0, 0.0, kPi / 2, 0.0, {0, 0, 0}, {0, 0.35, 0}, 200e-6, -62.6111},
    {0.4318, 0.0, 0.0, 17.4, {-0.3638, 0.006, 0.2275}, {0.13, 0.524, 0.539}, 200e-6, 107.815},
    {0.0203, 0.15005, -kPi / 2, 4.8, {-0.0203, -0.0141, 0.070}, {0.066, 0.086, 0.0125}, 200e-6, -53.7063},
    {0.0, 0.4318, kPi / 2, 0.82, {0, 0.019, 0}, {1.8e-3, 1.3e-3, 1.8e-3}, 33e-6, 76.0364},
    {0.0, 0.0, -kPi / 2, 0.34, {0, 0, 0}, {0.3e-3, 0.4e-3, 0.3e-3}, 33e-6, 71.923},
    {0.0, 0.0, 0.0, 0.09, {0, 0, 0.032}, {0.15e-3, 0.15e-3, 0.04e-3}, 33e-6, 76.686},
};

/// Gravity magnitude; gravity acts along -z0.
constexpr double kGravity = 9.81;

/// Joint limits [rad] (WC91 set, as in the MATLAB toolbox model).
constexpr double kQMin[kDof] = {-160 * kPi / 180, -45 * kPi / 180, -225 * kPi / 180,
                                -110 * kPi / 180, -100 * kPi / 180, -266 * kPi / 180};
constexpr double kQMax[kDof] = {160 * kPi / 180, 225 * kPi / 180, 45 * kPi / 180,
                                170 * kPi / 180, 100 * kPi / 180, 266 * kPi / 180};

/// Named poses [rad].
constexpr double kQz[kDof] = {0, 0, 0, 0, 0, 0};
constexpr double kQr[kDof] = {0, kPi / 2, -kPi / 2, 0, 0, 0};
constexpr double kQs[kDof] = {0, 0, -kPi / 2, 0, 0, 0};
constexpr double kQn[kDof] = {0, kPi / 4, kPi, 0, kPi / 4, 0};

/// Toolbox (Corke/Armstrong-Helouvry) motor-side friction: viscous B and Coulomb Tc(+), Tc(-).
constexpr double kMotorViscous[kDof] = {1.48e-3, 0.817e-3, 1.38e-3, 71.2e-6, 82.6e-6, 36.7e-6};
constexpr double kMotorCoulombPos[kDof] = {0.395, 0.126, 0.132, 11.2e-3, 9.26e-3, 3.96e-3};
constexpr double kMotorCoulombNeg[kDof] = {-0.435, -0.071, -0.105, -16.9e-3, -14.5e-3, -10.5e-3};

}  // namespace osc::puma560
