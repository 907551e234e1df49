# One small function per kind of target. Every target includes from the repository root,
# IRDIST_ROOT (this file's parent folder, also when fuzz/'s project builds the module libraries).
get_filename_component(IRDIST_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)

set(IRDIST_WARNINGS -Wall -Wextra -Wno-unused-parameter)

# irdist_library(NAME SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
function(irdist_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${IRDIST_ROOT})
  target_compile_options(${name} PRIVATE ${IRDIST_WARNINGS})
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  # -fPIC: the Python module (python/) links these static libraries into a shared object.
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# irdist_executable(NAME SOURCES ... [DEPS ...])
function(irdist_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_options(${name} PRIVATE ${IRDIST_WARNINGS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
endfunction()

# Tests that start a GigE Vision camera on 127.0.0.1:3956 (the virtual rig or Aravis's fake camera)
# run through irdist_loopback_netns (tests/loopback_netns.cc): each in a network namespace of its
# own with loopback up, so that no broadcast leaves the test; and one at a time (this CTest
# resource lock).
set(IRDIST_CAMERA_TESTS_LOCK irdist_camera_tests)
set(IRDIST_TEST_TIMEOUT_SCALE 1 CACHE STRING "Multiplier of every test's timeout (a sanitized build)")

# One precompiled header for every test (irdist_test_pch, built once): GoogleTest and the standard
# headers the tests use. Parsing gtest alone is about 1.5 s of each of the 200 test objects'
# compile, in the Release and the sanitized builds alike. A PCH is reused only by targets compiled
# with the very same flags and definitions (clang refuses any other), so every test gets the same:
# -pthread, IRDIST_TEST_COMMON_DEPS (glog's definitions, which Ceres brings to the tests that use
# it), IRDIST_SOURCE_DIR and IRDIST_BINARY_DIR, nothing of its own.
set(IRDIST_TEST_COMMON_DEPS GTest::gtest GTest::gmock GTest::gtest_main Threads::Threads glog::glog)
function(irdist_test_options target)
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR})
  # -O1 for the test's own code (after the build type's -O2/-O3, so it wins; not in Debug): a
  # test file's optimisation took three quarters of its compile time at -O3, and the suite's
  # computing is in the libraries, built at the build type's level.
  # -pthread on every test: glib's pkg-config flags bring it to some, and a PCH must match all.
  target_compile_options(${target} PRIVATE ${IRDIST_WARNINGS} -pthread
    $<$<NOT:$<CONFIG:Debug>>:-O1>)
  target_compile_definitions(${target} PRIVATE
    IRDIST_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    IRDIST_BINARY_DIR="${PROJECT_BINARY_DIR}")
endfunction()
# Made by the first irdist_test (fuzz/'s project includes this file and has no tests).
function(irdist_test_pch_target)
  file(WRITE ${PROJECT_BINARY_DIR}/irdist_test_pch.cc "// The tests' precompiled header's own unit.\n")
  add_library(irdist_test_pch STATIC ${PROJECT_BINARY_DIR}/irdist_test_pch.cc)
  irdist_test_options(irdist_test_pch)
  target_link_libraries(irdist_test_pch PRIVATE ${IRDIST_TEST_COMMON_DEPS})
  target_precompile_headers(irdist_test_pch PRIVATE
    <gtest/gtest.h> <gmock/gmock.h> <algorithm> <chrono> <cmath> <cstdint> <cstdio> <cstring>
    <filesystem> <fstream> <functional> <map> <memory> <optional> <set> <sstream> <string>
    <thread> <utility> <vector>)
endfunction()

# irdist_test(module/file SOURCES ... [DEPS ...] [TIMEOUT seconds] [LABELS ...] [GIGE])
# The CTest name is module/file, mirroring the source tree; the binary is test_module_file.
# GIGE: the test starts a camera on 127.0.0.1, so it runs through irdist_loopback_netns.
function(irdist_test test_name)
  cmake_parse_arguments(ARG "GIGE" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  string(REPLACE "/" "_" target "test_${test_name}")
  if(NOT TARGET irdist_test_pch)
    irdist_test_pch_target()
  endif()
  add_executable(${target} ${ARG_SOURCES})
  irdist_test_options(${target})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} ${IRDIST_TEST_COMMON_DEPS})
  target_precompile_headers(${target} REUSE_FROM irdist_test_pch)
  if(ARG_GIGE)
    add_test(NAME ${test_name}
      COMMAND irdist_loopback_netns $<TARGET_FILE:${target}>)
  else()
    add_test(NAME ${test_name} COMMAND ${target})
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  # A sanitized build runs some tests 20-30x slower (Ceres and Eigen under ASan+UBSan): its
  # configure sets IRDIST_TEST_TIMEOUT_SCALE (./irdist test --sanitize: 10).
  set(_cost ${ARG_TIMEOUT})
  if(IRDIST_TEST_TIMEOUT_SCALE)
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * ${IRDIST_TEST_TIMEOUT_SCALE}")
  endif()
  # COST orders a run without CTest's own timings (a fresh clone): the slowest tests first, so that
  # none is left running alone at the end; the unscaled timeout stands for the expected time.
  set_tests_properties(${test_name} PROPERTIES TIMEOUT ${ARG_TIMEOUT} COST ${_cost}
    WORKING_DIRECTORY ${PROJECT_BINARY_DIR})
  if(ARG_GIGE)
    # Label gige: `ctest -LE gige` runs the tests without a camera. Still one at a time: side by
    # side, the camera tests whose truth depends on time (a slide moving through an exposure, a
    # calibration at time scale 1) read 4-5 sd off or fail their fit under each other's load.
    list(APPEND ARG_LABELS gige)
    set_tests_properties(${test_name} PROPERTIES RESOURCE_LOCK ${IRDIST_CAMERA_TESTS_LOCK})
  endif()
  if(ARG_LABELS)
    set_tests_properties(${test_name} PROPERTIES LABELS "${ARG_LABELS}")
  endif()
endfunction()

# irdist_bench(NAME SOURCES ... [DEPS ...]): Google Benchmark binaries, never run by CTest.
function(irdist_bench name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_definitions(${name} PRIVATE
    IRDIST_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    IRDIST_BINARY_DIR="${PROJECT_BINARY_DIR}")
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} benchmark::benchmark)
endfunction()

# irdist_subdirs(): add every immediate subfolder that has a CMakeLists.txt.
macro(irdist_subdirs)
  file(GLOB _children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/*)
  foreach(_child ${_children})
    if(IS_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/${_child} AND EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${_child}/CMakeLists.txt)
      add_subdirectory(${_child})
    endif()
  endforeach()
endmacro()
