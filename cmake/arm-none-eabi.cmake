# Cross toolchain: arm-none-eabi-gcc for a Cortex-M core: the Cortex-M4F (hard float, single
# precision FPU) by default; a toolchain file for another core sets OSC_TARGET_CPU and includes this
# one (arm-none-eabi-m3.cmake: Cortex-M3, no FPU).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_OBJCOPY arm-none-eabi-objcopy)
set(CMAKE_SIZE arm-none-eabi-size)

# The CPU the boards built with this toolchain must have (boards/<board>/CMakeLists.txt).
if(NOT OSC_TARGET_CPU)
  set(OSC_TARGET_CPU cortex-m4f)
endif()
if(OSC_TARGET_CPU STREQUAL "cortex-m4f")
  set(OSC_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
elseif(OSC_TARGET_CPU STREQUAL "cortex-m3")
  set(OSC_CPU_FLAGS "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft")
else()
  message(FATAL_ERROR "arm-none-eabi.cmake: no flags for OSC_TARGET_CPU ${OSC_TARGET_CPU}")
endif()
set(CMAKE_C_FLAGS_INIT "${OSC_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${OSC_CPU_FLAGS} -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti -fno-threadsafe-statics -fno-use-cxa-atexit -fno-unwind-tables -fno-asynchronous-unwind-tables")
# -O3: measured against -O2 and -Os on both cores (docs/benchmarks.md, "Optimisation level"). CMake
# appends its own Release default (-O3 -DNDEBUG) to these, so that is what every image has been
# built with; -O2 here before was overridden by it.
set(CMAKE_CXX_FLAGS_RELEASE_INIT "-O3 -DNDEBUG")
set(CMAKE_C_FLAGS_RELEASE_INIT "-O3 -DNDEBUG")
# Own startup code; newlib-nano for the few libc/libm functions used; no syscall stubs (libnosys
# would provide _sbrk, i.e. a heap).
set(CMAKE_EXE_LINKER_FLAGS_INIT "${OSC_CPU_FLAGS} -nostartfiles --specs=nano.specs -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
# Packages from the host too: Eigen's (header-only; the top-level CMakeLists.txt finds it).
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
