# station/plan: the sweep plan's tests (owned by app's engineer). Included by
# tests/station/CMakeLists.txt and, while that does not include it, by tests/app/CMakeLists.txt;
# the guard keeps it to one definition.
if(NOT TARGET test_station_plan)
  irdist_test(station/plan
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/plan_test.cc
    DEPS irdist_sweep_plan
    TIMEOUT 60)
endif()
