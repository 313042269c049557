// Q-format fixed-point scalars: the kernels' arithmetic on cores without an FPU
// (docs/fixed_point.md has the formats, the headroom analysis and the measured errors).
//
// Q<F> is a signed 32-bit integer r that stands for r / 2^F: 31 - F integer bits, F fraction bits.
// Products and quotients go through 64-bit intermediates and are rounded to nearest. A result that
// does not fit saturates at the end of the range and raises a sticky flag, never silently:
//   kOverflow  a sum, product, negation or conversion beyond the range;
//   kDivision  a division by zero, or by a number so near zero that the quotient does not fit;
//   kDomain    a function outside its domain (sqrt of a negative, asin beyond [-1, 1], NaN input).
// The control task reads and clears the flags once per tick (math::take_arithmetic_fault) and the
// supervisor latches them as the fault `overflow`, with zero torque in the same tick.
//
// The family of formats, by quantity:
//   Fixed   = Q<19> (Q12.19, range +-4096, resolution 1.9e-6): every kernel and control-law quantity
//             (angles, positions, velocities, forces, torques, inertias, gains, time).
//   FixedIo = Q<12> (Q19.12, range +-524288, resolution 2.4e-4): hardware units at the I/O boundary
//             (encoder counts, counts per radian, DAC codes): math::io_scalar_t<Fixed>.
//   Q1.30 in 32 bits and Q30 / Q61 in 64 bits: inside the elementary functions (and Q1.30 for
//   the coefficients, Q5.26, Q6.25 and Q9.22 for the states of the identification filter:
//   osc/control/identify_filter.hpp).
// The elementary functions (sin, cos, exp, atan2, asin, sqrt) take and return Q<F>; their maximum
// errors against double over the whole input range are stated at each and tested in
// tests/firmware/math/test_q_functions.cpp.
//
// The parts: osc/math/saturating_int.hpp (the flags and the saturating integer arithmetic),
// osc/math/q.hpp (the type Q<F>, Fixed and FixedIo), osc/math/q_functions.hpp (the elementary
// functions and their error bounds), osc/math/q_eigen.hpp (Eigen's NumTraits and one-rounding dot
// products). This header includes them all.
#pragma once

#include "osc/math/q.hpp"
#include "osc/math/q_eigen.hpp"
#include "osc/math/q_functions.hpp"
