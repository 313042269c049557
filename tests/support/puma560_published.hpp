// The published PUMA 560 test vectors of ../shared/reference/puma560.md (sections 5 and 6), written
// once: the host's tests (tests/firmware/kernels/test_published.cpp) and the target images' checks
// (tests/boards/mps2/kernels_image.cpp) both read them from here. Row-major where a matrix; printed
// to 4 decimals (6 significant digits for the inverse dynamics), as published.
#pragma once

#include <string_view>

#include "osc/robot.hpp"
#include "osc/robots/puma560.hpp"

namespace osc::test {
/// The build's arm is the PUMA 560 (CMake OSC_ROBOT=puma560, the default): the vectors below are its.
inline constexpr bool kPumaBuild = std::string_view(robot::kArm.name) == std::string_view(puma560::kArm.name);
}  // namespace osc::test

namespace osc::test::published {

/// gravload(qn): the gravity torques at the nominal pose qn [N m].
inline constexpr double kGravityQn[6] = {0, 31.6399, 6.0351, 0, 0.0283, 0};
/// rne(qn, qd, qdd) with the toolbox's friction, gravity on (off: kRneOneOneNoGravity) [N m].
inline constexpr double kRneZeroOne[6] = {3.35311, 36.0025, 7.42596, 0.190043, 0.203441, 0.194133};
inline constexpr double kRneOneOne[6] = {32.4952, 60.867, 17.7436, 1.45452, 1.29911, 0.713781};
inline constexpr double kRneOneZero[6] = {29.1421, 56.5044, 16.3528, 1.26448, 1.12392, 0.519648};
inline constexpr double kRneOneOneNoGravity[6] = {32.4952, 29.2271, 11.7085, 1.45452, 1.27086, 0.713781};
/// rne(qn, 0, 0) with the wrench fext = [1 2 3 1 2 3] exerted by the end effector (frame 6) [N m].
inline constexpr double kRneWrench[6] = {0.642756, 29.0866, 4.70321, 2.82843, -1.97175, 3};
/// inertia(qn) * [1 2 3 1 2 3].
inline constexpr double kInertiaTimesQdd[6] = {3.1500, 9.4805, 3.6189, 0.1901, 0.3519, 0.5823};
/// accel(qn, qd = [0.1 0.2 0.8 0.2 0.5 1.0], tau = [1.0 3.2 1.8 0.1 0.7 4.6]) [rad/s^2].
inline constexpr double kAccel[6] = {-7.4102, -9.8432, -10.9694, -4.4314, -0.9881, 21.0228};
/// inertia(qn) [kg m^2].
inline constexpr double kInertiaQn[36] = {3.6594,  -0.4044, 0.1006, -0.0025, 0.0000, -0.0000,  //
                                          -0.4044, 4.4137,  0.3509, 0.0000,  0.0024, 0.0000,   //
                                          0.1006,  0.3509,  0.9378, 0.0000,  0.0015, 0.0000,   //
                                          -0.0025, 0.0000,  0.0000, 0.1925,  0.0000, 0.0000,   //
                                          0.0000,  0.0024,  0.0015, 0.0000,  0.1713, 0.0000,   //
                                          -0.0000, 0.0000,  0.0000, 0.0000,  0.0000, 0.1941};
/// coriolis(qn, qd = [1 2 3 1 2 3]).
inline constexpr double kCoriolisQn[36] = {-0.1735, -2.0494, -0.1178, -0.0002, -0.0045, 0.0001,   //
                                           0.6274,  1.1572,  1.9287,  -0.0015, -0.0003, -0.0000,  //
                                           -0.3608, -0.7734, -0.0018, -0.0009, -0.0064, -0.0000,  //
                                           0.0011,  0.0005,  -0.0001, 0.0002,  0.0002,  -0.0001,  //
                                           -0.0002, 0.0028,  0.0046,  -0.0002, -0.0000, -0.0000,  //
                                           0.0001,  0.0000,  0.0000,  0.0000,  0.0000,  0};
/// The operational inertia Lambda at qn through the geometric Jacobian.
inline constexpr double kLambdaQn[36] = {17.2954, -2.7542, -9.6233, -0.0000, 0.2795,  0.0000,   //
                                         -2.7542, 12.1909, 1.2459,  -0.3254, -0.0703, -0.9652,  //
                                         -9.6233, 1.2459,  13.3348, -0.0000, 0.2767,  -0.0000,  //
                                         -0.0000, -0.3254, -0.0000, 0.1941,  0.0000,  0.1941,   //
                                         0.2795,  -0.0703, 0.2767,  0.0000,  0.1713,  0.0000,   //
                                         0.0000,  -0.9652, -0.0000, 0.1941,  0.0000,  0.5791};
/// fkine(qn): the tip position [m] (its rotation: [0 0 1; 0 1 0; -1 0 0]).
inline constexpr double kTipQn[3] = {0.59630, -0.15005, -0.01435};
/// jacob0(qn), row-major.
inline constexpr double kJacobianQn[36] = {0.1501, 0.0144, 0.3197, 0,       0,  0,  //
                                           0.5963, 0,      0,      0,       0,  0,  //
                                           0,      0.5963, 0.2910, 0,       0,  0,  //
                                           0,      0,      0,      0.7071,  0,  1,  //
                                           0,      -1,     -1,     0,       -1, 0,  //
                                           1,      0,      0,      -0.7071, 0,  0};
/// fkine(qz): the tip's x and z [m]; inertia(qz): its diagonal and three off-diagonal entries;
/// gravload(qz).
inline constexpr double kTipQzX = 0.45210, kTipQzZ = 0.43180;
inline constexpr double kInertiaQzDiagonal[6] = {3.9611, 4.4566, 0.9387, 0.1924, 0.1713, 0.1941};
inline constexpr double kInertiaQz12 = -0.1627, kInertiaQz13 = -0.1389, kInertiaQz23 = 0.3727;
inline constexpr double kGravityQz[6] = {0, 37.4837, 0.2489, 0, 0, 0};

}  // namespace osc::test::published
