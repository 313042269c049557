# The boards/<board>/CMakeLists.txt of an MPS2 board built from CMSDK parts (mps2-an385, mps2-an386):
# one call of osc_add_mps2_board(NAME CPU QEMU_MACHINE PIL_SCALAR DOCS_TABLES). The wiring, the interrupt table, the linker
# script and the images are shared (boards/common/mps2, linker/mps2.ld); the board's own folder has
# its board.hpp (the core and the scalar of its images, board::Scalar) and this call. Defines the
# images kernels_image, heap_probe, pil_firmware, timer_firmware and watchdog_firmware (all but
# pil_firmware are tests, with their sources in tests/boards/) with their
# tests (FORBIDDEN_ON_CONTROL_PATH: a regular expression of routines the control path must not call); sets OSC_BOARD_ENABLED in the caller (false when CPU is not this toolchain's).
set(OSC_MPS2_DIR ${CMAKE_CURRENT_LIST_DIR})
# The test images (kernels_image, timer_firmware, watchdog_firmware) live with the tests.
set(OSC_MPS2_TESTS_DIR ${PROJECT_SOURCE_DIR}/tests/boards/mps2)

function(osc_add_mps2_board)
  cmake_parse_arguments(B "" "NAME;CPU;QEMU_MACHINE;FORBIDDEN_ON_CONTROL_PATH;PIL_SCALAR;DOCS_TABLES" "" ${ARGN})
  osc_add_board(NAME ${B_NAME} CPU ${B_CPU} LINKER_SCRIPT ${PROJECT_SOURCE_DIR}/linker/mps2.ld
                QEMU_MACHINE ${B_QEMU_MACHINE} SOURCES ${OSC_MPS2_DIR}/vectors.cpp)
  set(OSC_BOARD_ENABLED ${OSC_BOARD_ENABLED} PARENT_SCOPE)
  if(NOT OSC_BOARD_ENABLED)
    return()
  endif()
  target_include_directories(board_${B_NAME} PUBLIC ${OSC_MPS2_DIR})
  target_link_libraries(board_${B_NAME} PUBLIC cmsdk)  # the CMSDK watchdog driver

  # Every kernel in the board's scalar against the published vectors (and, in fixed point, the
  # host's results bit for bit: tests/support/fixed_reference.hpp), with per-kernel instruction counts.
  osc_board_image(${B_NAME} kernels_image ${OSC_MPS2_TESTS_DIR}/kernels_image.cpp)
  target_include_directories(kernels_image PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
  add_test(NAME kernels_image_qemu COMMAND kernels_image)
  osc_image_checks(kernels_image)

  # The link-time heap ban: an image that calls malloc must fail to link.
  osc_board_image(${B_NAME} heap_probe ${PROJECT_SOURCE_DIR}/tests/boards/cortex_m/heap_probe.cpp)
  set_target_properties(heap_probe PROPERTIES EXCLUDE_FROM_ALL TRUE)
  add_test(NAME heap_use_fails_link COMMAND ${CMAKE_COMMAND} --build ${CMAKE_BINARY_DIR} --target heap_probe)
  # Passes only on the linker script's heap assertion (not on any other build failure).
  set_tests_properties(heap_use_fails_link PROPERTIES PASS_REGULAR_EXPRESSION "heap use is forbidden")

  # Processor-in-the-loop firmware: the control task over the UART0 link to host_sim.
  osc_board_image(${B_NAME} pil_firmware ${OSC_MPS2_DIR}/pil_firmware.cpp)
  # Its parameter store on a host file ("params=PATH" on its semihosting command line: semihost_flash.hpp).
  target_link_libraries(pil_firmware PRIVATE param_store)
  osc_image_checks(pil_firmware)

  # The control path (the timer interrupt, the tick, the step) calls no routine the board's scalar
  # must not need: FORBIDDEN_ON_CONTROL_PATH, e.g. the soft double-precision routines.
  find_program(OSC_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  foreach(image pil_firmware timer_firmware)
    add_test(NAME ${image}_control_path_calls
             COMMAND ${OSC_SYSTEM_PYTHON} ${OSC_CORTEX_M_DIR}/control_path_calls.py $<TARGET_FILE:${image}>
                     "^TIMER0_Handler$|control_tick|control_step" "${B_FORBIDDEN_ON_CONTROL_PATH}"
                     --objdump ${CMAKE_OBJDUMP})
  endforeach()

  # The control task in the real 1 kHz timer interrupt (no plant).
  osc_board_image(${B_NAME} timer_firmware ${OSC_MPS2_TESTS_DIR}/timer_firmware.cpp)
  add_test(NAME timer_firmware_qemu COMMAND timer_firmware)
  # The image feeds the watchdog; under -no-reboot a watchdog reset would end QEMU with status 0,
  # so the test also needs the image's own verdict.
  set_tests_properties(timer_firmware_qemu PROPERTIES PASS_REGULAR_EXPRESSION "timer_firmware: pass")
  # The same image measuring the tick's worst case (docs/benchmarks.md): the momentum law's gates
  # open and its blocks of 4 samples (params::kTickWorstCase), so that its 200 ticks hold Kalman
  # updates and folds although the arm is at rest, and the arm's own encoders (robot::kDriveTrain: on
  # the PUMA the coupled wrist, whose friction law is the drives'). A measurement image only.
  osc_board_image(${B_NAME} timer_worst_firmware ${OSC_MPS2_TESTS_DIR}/timer_firmware.cpp)
  target_compile_definitions(timer_worst_firmware PRIVATE OSC_TICK_WORST_CASE)
  add_test(NAME timer_worst_firmware_qemu COMMAND timer_worst_firmware)
  set_tests_properties(timer_worst_firmware_qemu PROPERTIES PASS_REGULAR_EXPRESSION "timer_firmware: pass")

  # The watchdog end to end: healthy ticks feed it; a hung tick, a latched fault and a disabled
  # control interrupt each let it reset the board (QEMU reboots the image; a record in .noinit RAM
  # carries the scenario across the resets).
  osc_board_image(${B_NAME} watchdog_firmware ${OSC_MPS2_TESTS_DIR}/watchdog_firmware.cpp)
  osc_add_reboot_test(watchdog_reset_qemu watchdog_firmware)
  set_tests_properties(watchdog_reset_qemu PROPERTIES PASS_REGULAR_EXPRESSION "watchdog_firmware: pass")

  # The host's PIL tests against pil_firmware, the host controller in PIL_SCALAR; the generated
  # tables of docs/ of kind DOCS_TABLES (scripts/docs_tables.py) current for this build's images.
  osc_add_pil_tests(${B_PIL_SCALAR})
  osc_add_motion_tests(${B_PIL_SCALAR})
  # The virtual board over the image: on the M4F's only (it runs in real time, 30 s of the CI's; the
  # M3's image behind osc_sim --pty --qemu --scalar fixed is the same relay).
  if(B_PIL_SCALAR STREQUAL "float")
    osc_add_virtual_board_test(${B_PIL_SCALAR})
  endif()
  osc_add_docs_tables_test(${B_DOCS_TABLES})
endfunction()

# osc_add_virtual_board_test(SCALAR): virtual_board_qemu_sequence: the host build's osc_sim --pty
# --qemu serves this build's pil_firmware (computing in SCALAR) on a pseudo-terminal in real time,
# driven by the host build's oscctl and the Python client (tests/cli/virtual_board.sh qemu_sequence;
# docs/motion.md, "The virtual board").
function(osc_add_virtual_board_test scalar)
  osc_host_tool(OSC_SIM_BOARD osc_sim host_sim)
  osc_host_tool(OSC_OSCCTL oscctl host_sim)
  find_program(OSC_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(NOT OSC_SYSTEM_PYTHON)
    return()
  endif()
  add_test(NAME virtual_board_qemu_sequence
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/cli/virtual_board.sh ${OSC_SIM_BOARD} ${OSC_OSCCTL}
                   ${OSC_SYSTEM_PYTHON} ${PROJECT_SOURCE_DIR}/clients/python/src qemu_sequence
                   $<TARGET_FILE:pil_firmware> ${scalar})
  # About 20 s simulated, in real time (slower on a busy machine: QEMU then falls behind). The Python
  # client reads the protocol of the host build for the same arm (OSC_HOST_CLIENT_PROTOCOL_ENV).
  set_tests_properties(virtual_board_qemu_sequence PROPERTIES DEPENDS pil_firmware_checks TIMEOUT 600 ENVIRONMENT
                                                              "${OSC_HOST_CLIENT_PROTOCOL_ENV}")
  # The image's capture (issue 58): triggered by an injected fault, read out and drawn by the Python client.
  add_test(NAME virtual_board_qemu_capture
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/cli/virtual_board.sh ${OSC_SIM_BOARD} ${OSC_OSCCTL}
                   ${OSC_SYSTEM_PYTHON} ${PROJECT_SOURCE_DIR}/clients/python/src qemu_capture
                   $<TARGET_FILE:pil_firmware> ${scalar})
  set_tests_properties(virtual_board_qemu_capture PROPERTIES DEPENDS pil_firmware_checks TIMEOUT 600 ENVIRONMENT
                                                             "${OSC_HOST_CLIENT_PROTOCOL_ENV}")
  # A power cycle of the image (issue 57): its store in a file that a restart applies (tests/cli/virtual_board.sh
  # qemu_power_cycle: the estimate from the PUMA's identify pose, in process).
  if(OSC_ROBOT STREQUAL "puma560")
    add_test(NAME virtual_board_qemu_power_cycle
             COMMAND bash ${PROJECT_SOURCE_DIR}/tests/cli/virtual_board.sh ${OSC_SIM_BOARD} ${OSC_OSCCTL}
                     ${OSC_SYSTEM_PYTHON} ${PROJECT_SOURCE_DIR}/clients/python/src qemu_power_cycle
                     $<TARGET_FILE:pil_firmware> ${scalar})
    set_tests_properties(virtual_board_qemu_power_cycle PROPERTIES DEPENDS pil_firmware_checks TIMEOUT 600
                                                                   ENVIRONMENT "${OSC_HOST_CLIENT_PROTOCOL_ENV}")
  endif()
  # The command link's recovery over the image (tests/cli/link_recovery.py --qemu): the same outcomes
  # as in process.
  add_test(NAME virtual_board_qemu_link_recovery
           COMMAND ${OSC_SYSTEM_PYTHON} ${PROJECT_SOURCE_DIR}/tests/cli/link_recovery.py ${OSC_SIM_BOARD}
                   ${PROJECT_SOURCE_DIR}/clients/python/src --qemu $<TARGET_FILE:pil_firmware>)
  set_tests_properties(virtual_board_qemu_link_recovery PROPERTIES DEPENDS pil_firmware_checks TIMEOUT 300
                                                                   ENVIRONMENT "${OSC_HOST_CLIENT_PROTOCOL_ENV}")
endfunction()

# osc_add_motion_tests(SCALAR): scripted motions on this build's pil_firmware in QEMU (the host
# build's puma_experiment --motion --qemu, docs/motion.md): motion_tour_qemu plays
# examples/motion_tour.yaml on the image and in process in SCALAR and compares the two JSON outputs
# bit for bit (tests/cli/motion_scripts.sh qemu_tour; in float with the host-scalar build's
# puma_experiment, whose float controller has no SIMD, as the M4F's); motion_qemu_wrong_scalar and
# motion_qemu_start_pose, what --qemu refuses.
function(osc_add_motion_tests scalar)
  if(scalar STREQUAL "float")
    osc_host_tool(OSC_PUMA_EXPERIMENT puma_experiment host_sim ${OSC_HOST_SCALAR_TOOLS_DIR})
  else()
    osc_host_tool(OSC_PUMA_EXPERIMENT puma_experiment host_sim)
  endif()
  find_program(OSC_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(NOT OSC_SYSTEM_PYTHON)
    return()
  endif()
  set(motion bash ${PROJECT_SOURCE_DIR}/tests/cli/motion_scripts.sh ${OSC_PUMA_EXPERIMENT} ${OSC_SYSTEM_PYTHON}
             ${PROJECT_SOURCE_DIR}/examples)
  add_test(NAME motion_tour_qemu COMMAND ${motion} qemu_tour $<TARGET_FILE:pil_firmware> ${scalar})
  # 37 s simulated: about 15 s under QEMU on an idle machine, a minute on a busy one.
  set_tests_properties(motion_tour_qemu PROPERTIES DEPENDS pil_firmware_checks TIMEOUT 600)
  if(scalar STREQUAL "fixed")
    set(wrong float)
  else()
    set(wrong fixed)
  endif()
  add_test(NAME motion_qemu_wrong_scalar COMMAND ${motion} qemu_wrong_scalar $<TARGET_FILE:pil_firmware> ${wrong})
  add_test(NAME motion_qemu_start_pose COMMAND ${motion} qemu_start_pose $<TARGET_FILE:pil_firmware>)
endfunction()

# osc_add_pil_test(NAME SCALAR LINK [ARGS...]): the host's PIL tests (OSC_TEST_PIL: the host build's
# tests/test_pil, in OSC_HOST_TOOLS_DIR; the host preset must be built first, scripts/test.sh does)
# against this build's pil_firmware in QEMU over LINK (semihosting or uart, host_sim/pil_client.hpp):
# fault injection through the link and the closed loop against the host-built controller in SCALAR
# (float or fixed).
# With LOADED N before the arguments, the test runs while N busy processes compete for the cores
# (tests/support/run_under_load.sh).
function(osc_add_pil_test name scalar link)
  cmake_parse_arguments(PARSE_ARGV 3 PIL "" "LOADED" "")
  set(cmd ${OSC_TEST_PIL} ${PIL_UNPARSED_ARGUMENTS})
  if(PIL_LOADED)
    set(cmd bash ${PROJECT_SOURCE_DIR}/tests/support/run_under_load.sh ${PIL_LOADED} ${cmd})
  endif()
  add_test(NAME ${name} COMMAND ${cmd})
  set_tests_properties(${name} PROPERTIES
    ENVIRONMENT "PIL_FIRMWARE_ELF=$<TARGET_FILE:pil_firmware>;QEMU=${QEMU_SYSTEM_ARM};PIL_SCALAR=${scalar};PIL_LINK=${link}"
    DEPENDS pil_firmware_checks TIMEOUT 900)
  # The load is this test's own: it runs alone, so that it does not load the others. pil_qemu's
  # comparison of the UART with the semihosting console needs a clean UART link for 3 s; it failed
  # once when it ran beside this test's two busy processes (a 4 s gap of the firmware's clock, a
  # silence, and then 184 ticks that differed).
  if(PIL_LOADED)
    set_tests_properties(${name} PROPERTIES RUN_SERIAL TRUE)
  endif()
endfunction()

# osc_add_pil_tests(SCALAR): every PIL test, each over the transport it needs. Over the
# semihosting console (the experiment's default): all but the link's timeouts, which that transport
# does not have (the firmware blocks in its read, and virtual time with it); PilQemu compares it
# with the UART bit for bit. Over the UART, byte by byte as on a board: the link tests, timeouts
# included.
function(osc_add_pil_tests scalar)
  osc_host_tool(OSC_TEST_PIL test_pil tests)
  osc_add_pil_test(pil_qemu ${scalar} semihosting
                   --gtest_filter=-Link.ShortFrameTimesOutWithZeroCodes:Link.SilenceGetsZeroCodesRepeatedSilenceLatchesLinkLost)
  osc_add_pil_test(pil_qemu_uart ${scalar} uart --gtest_filter=Link.*)
  # The same on a machine kept busy: QEMU's virtual time follows the wall clock while the firmware
  # waits, so a descheduled emulator is a long wait to it (once a watchdog reset: pil_firmware.cpp).
  osc_add_pil_test(pil_qemu_uart_loaded ${scalar} uart LOADED 2 --gtest_filter=Link.*)
endfunction()

# osc_add_docs_tables_test(KIND): ctest docs_tables_KIND checks that the generated tables of that
# kind in docs/ (scripts/docs_tables.py --kind KIND) are current for this build's images.
# Only in a build for the default arm (the PUMA 560), whose images the tables are.
function(osc_add_docs_tables_test kind)
  find_program(OSC_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(OSC_SYSTEM_PYTHON AND OSC_ROBOT STREQUAL "puma560")
    add_test(NAME docs_tables_${kind}
             COMMAND ${OSC_SYSTEM_PYTHON} ${PROJECT_SOURCE_DIR}/scripts/docs_tables.py --check --kind ${kind}
                     --${kind}-build ${CMAKE_BINARY_DIR})
  endif()
endfunction()
