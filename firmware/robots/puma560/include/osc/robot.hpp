// The robot this build is for (CMake OSC_ROBOT=puma560): the PUMA 560.
#pragma once

#include "osc/robots/puma560.hpp"

namespace osc {
namespace robot = puma560;
}
