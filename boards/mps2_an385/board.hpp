// Board support for QEMU's mps2-an385: Arm MPS2 with the AN385 FPGA image, a Cortex-M3 without an
// FPU, with the AN386's memory map and CMSDK peripherals (boards/common/mps2/mps2.hpp). The images
// compute the control law in Q12.19 fixed point (osc/math/fixed.hpp, docs/fixed_point.md);
// kernels_image_softfloat computes it in float through the compiler's soft-float routines, to
// measure the alternative.
#pragma once

#include "mps2.hpp"
#include "osc/math/fixed.hpp"

namespace board {

constexpr const char* kCore = "Cortex-M3";
#if defined(OSC_IMAGE_SOFT_FLOAT)
using Scalar = float;
constexpr const char* kScalarName = "float (soft-float routines)";
#else
/// The scalar of the images' control law.
using Scalar = osc::Fixed;
constexpr const char* kScalarName = "Q12.19 fixed point";
#endif

}  // namespace board
