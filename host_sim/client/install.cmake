# The C++ client as an installed package (docs/motion.md, "The C++ client installed"):
#
#   cmake --install BUILD --component osc_client --prefix PREFIX
#
# puts the static library in PREFIX/lib, its headers in PREFIX/include/osc_client/ and the package
# in PREFIX/lib/cmake/osc_client/, for a program's
#
#   find_package(osc_client REQUIRED)        # -DCMAKE_PREFIX_PATH=PREFIX
#   target_link_libraries(prog PRIVATE osc::osc_client)
#
# The headers are osc_client.hpp, stream_path.hpp and every firmware header they include (the link
# protocol's frames and codes, the robot description of this build's arm, osc/robot.hpp, and the
# layers under them), each at its path below its include directory (osc/link/frames.hpp ...): the
# compiler lists them when the package is installed (install_headers.cmake), so the set follows the
# includes. The installed target carries C++20 and Eigen (found again by the package's config); the
# arm is this build's OSC_ROBOT, the package's osc_client_ROBOT. Included by host_sim/CMakeLists.txt.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(OSC_CLIENT_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/osc_client)
set(OSC_CLIENT_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/osc_client)
target_include_directories(osc_client INTERFACE $<INSTALL_INTERFACE:${OSC_CLIENT_INCLUDEDIR}>)
target_link_libraries(osc_client INTERFACE $<INSTALL_INTERFACE:Eigen3::Eigen>)

install(TARGETS osc_client EXPORT osc_clientTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT osc_client)
install(EXPORT osc_clientTargets NAMESPACE osc:: DESTINATION ${OSC_CLIENT_CMAKEDIR} COMPONENT osc_client)

# The headers: those the compiler reads for a file that includes osc_client.hpp, with the client's
# include directories (the firmware layers' under osc_link, the generated osc/robot.hpp's); the
# directories outside the project (Eigen's) are system ones, not installed.
set(OSC_CLIENT_HEADER_PROBE ${CMAKE_CURRENT_BINARY_DIR}/osc_client_headers.cpp)
file(GENERATE OUTPUT ${OSC_CLIENT_HEADER_PROBE} CONTENT "#include \"osc_client.hpp\"\n")
install(CODE "
  set(OSC_CXX \"${CMAKE_CXX_COMPILER}\")
  set(OSC_PROBE \"${OSC_CLIENT_HEADER_PROBE}\")
  set(OSC_DIRS \"$<TARGET_PROPERTY:osc_client,INCLUDE_DIRECTORIES>\")
  set(OSC_PROJECT_DIRS \"${PROJECT_SOURCE_DIR};${PROJECT_BINARY_DIR}\")
  set(OSC_DEST \"\${CMAKE_INSTALL_PREFIX}/${OSC_CLIENT_INCLUDEDIR}\")
  include(\"${CMAKE_CURRENT_LIST_DIR}/install_headers.cmake\")"
  COMPONENT osc_client)

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/osc_clientConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/osc_clientConfig.cmake
                              INSTALL_DESTINATION ${OSC_CLIENT_CMAKEDIR} NO_SET_AND_CHECK_MACRO)
# 0.x: a minor version may change the protocol.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/osc_clientConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/osc_clientConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/osc_clientConfigVersion.cmake
        DESTINATION ${OSC_CLIENT_CMAKEDIR} COMPONENT osc_client)
