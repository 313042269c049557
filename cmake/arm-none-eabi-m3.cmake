# Cross toolchain for the Cortex-M3 (no FPU; preset m3): the common arm-none-eabi settings.
set(OSC_TARGET_CPU cortex-m3)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
