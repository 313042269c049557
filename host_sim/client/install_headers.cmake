# Run by cmake --install (install.cmake's install(CODE)): installs the client's headers and every
# header they include, as the compiler finds them (-MM: the headers a file that includes
# osc_client.hpp reads, system ones left out), each under OSC_DEST at its path below the include
# directory it is in (firmware/link/include/osc/link/frames.hpp -> OSC_DEST/osc/link/frames.hpp).
#
# In: OSC_CXX (the compiler), OSC_PROBE (the file including osc_client.hpp), OSC_DIRS (the client's
# include directories, in their order), OSC_PROJECT_DIRS (the source and build trees: directories
# elsewhere, Eigen's, are system ones), OSC_DEST (the install folder).
set(args -std=c++20 -MM)
set(own_dirs "")
foreach(dir IN LISTS OSC_DIRS)
  cmake_path(NORMAL_PATH dir)
  set(own FALSE)
  foreach(root IN LISTS OSC_PROJECT_DIRS)
    cmake_path(IS_PREFIX root "${dir}" NORMALIZE own_here)
    if(own_here)
      set(own TRUE)
    endif()
  endforeach()
  if(own)
    list(APPEND args -I${dir})
    list(APPEND own_dirs ${dir})
  else()
    list(APPEND args -isystem ${dir})
  endif()
endforeach()
execute_process(COMMAND ${OSC_CXX} ${args} ${OSC_PROBE} OUTPUT_VARIABLE deps ERROR_VARIABLE err
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "osc_client's headers: ${OSC_CXX} -MM ${OSC_PROBE} failed:\n${err}")
endif()
# "probe.o: probe.cpp a.hpp \
#   b.hpp ...": the files after the colon, the probe itself left out.
string(REGEX REPLACE "^[^:]*:" "" deps "${deps}")
string(REPLACE "\\\n" " " deps "${deps}")
string(STRIP "${deps}" deps)
separate_arguments(deps UNIX_COMMAND "${deps}")
set(count 0)
foreach(file IN LISTS deps)
  cmake_path(ABSOLUTE_PATH file NORMALIZE)
  if(file STREQUAL OSC_PROBE)
    continue()
  endif()
  set(rel "")
  foreach(dir IN LISTS own_dirs)  # the first that holds it, as the compiler searched them
    cmake_path(IS_PREFIX dir "${file}" NORMALIZE inside)
    if(inside)
      cmake_path(RELATIVE_PATH file BASE_DIRECTORY "${dir}" OUTPUT_VARIABLE rel)
      break()
    endif()
  endforeach()
  if(rel STREQUAL "")
    message(FATAL_ERROR "osc_client's headers: ${file} is in none of the client's include directories")
  endif()
  cmake_path(GET rel PARENT_PATH sub)
  cmake_path(APPEND OSC_DEST "${sub}" OUTPUT_VARIABLE to)
  file(INSTALL DESTINATION "${to}" TYPE FILE FILES "${file}")
  math(EXPR count "${count} + 1")
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "osc_client's headers: ${OSC_CXX} -MM listed none")
endif()
