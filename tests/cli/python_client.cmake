# The Python client's package (clients/python; README.md, "Python client"): its unit tests (pytest,
# clients/python/tests), its types (mypy --strict) and style (flake8), and its install offline into a
# new virtual environment (python_install.sh). Python only: in the host build, not the sanitizer one.
set(OSC_PYTHON_CLIENT_DIR ${PROJECT_SOURCE_DIR}/clients/python)
set(OSC_PYTHON_CLIENT_SRC ${OSC_PYTHON_CLIENT_DIR}/src)
if(OSC_SYSTEM_PYTHON AND NOT OSC_FUZZ)
  add_test(NAME python_client_pytest COMMAND ${OSC_SYSTEM_PYTHON} -m pytest -q ${OSC_PYTHON_CLIENT_DIR})
  add_test(NAME python_client_mypy
           COMMAND ${OSC_SYSTEM_PYTHON} -m mypy --config-file ${OSC_PYTHON_CLIENT_DIR}/pyproject.toml
                   --cache-dir ${CMAKE_CURRENT_BINARY_DIR}/mypy_cache ${OSC_PYTHON_CLIENT_SRC}
                   ${OSC_PYTHON_CLIENT_DIR}/tests)
  # setup.cfg's [flake8] (the project's line length), read from the source tree's root.
  add_test(NAME python_client_flake8 COMMAND ${OSC_SYSTEM_PYTHON} -m flake8 ${OSC_PYTHON_CLIENT_DIR}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python_client_pytest python_client_mypy python_client_flake8 PROPERTIES
                       ENVIRONMENT "PYTHONDONTWRITEBYTECODE=1" TIMEOUT 120)
  # Installed, the program reads the virtual board's state (osc_sim --pty).
  add_test(NAME python_client_install
           COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/python_install.sh ${OSC_SYSTEM_PYTHON} ${OSC_PYTHON_CLIENT_DIR}
                   $<TARGET_FILE:osc_sim_board>)
  set_tests_properties(python_client_install PROPERTIES TIMEOUT 300)
endif()
