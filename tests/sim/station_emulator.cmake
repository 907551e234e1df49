# sim/station_emulator: the station emulator over a real pty, spoken to with raw framed lines
# (no station/ code: the far side of the wire is tested on its own). Included by
# tests/sim/CMakeLists.txt. The emulator's source is compiled in directly so that this test does
# not wait for the rest of the virtual rig to build.
if(NOT TARGET test_sim_station_emulator)
  irdist_test(sim/station_emulator
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/station_emulator_test.cc
            ${PROJECT_SOURCE_DIR}/sim/station_emulator.cc
    DEPS irdist_base yaml-cpp Threads::Threads
    TIMEOUT 60)
endif()
