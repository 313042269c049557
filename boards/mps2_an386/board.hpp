// Board support for QEMU's mps2-an386: Arm MPS2 with the AN386 FPGA image, a Cortex-M4F with a
// single-precision FPU. The wiring is the MPS2 boards' (boards/common/mps2/mps2.hpp); the images
// compute the control law in float on the FPU.
#pragma once

#include "mps2.hpp"

namespace board {

constexpr const char* kCore = "Cortex-M4F";
/// The scalar of the images' control law.
using Scalar = float;
constexpr const char* kScalarName = "float";

}  // namespace board
