# caustics_add_gtest(SOURCE [LIBRARIES...]): one GoogleTest program per test file, every case
# discovered by ctest. The program links the whole framework and the shared test helpers
# (caustics_testing, cmake/CausticsInstall.cmake); tests that
# start the `caustics` program find it through CAUSTICS_BINARY, and test data through
# CAUSTICS_SOURCE_DIR (tests run from the source tree).
#
# Under the sanitizers every report ends the process (and so fails the test), also in the `caustics`
# children the tests start: ASan halts on its first error by default, and undefined behaviour is compiled
# with -fno-sanitize-recover (CMakeLists.txt), so UBSan halts too. Leak checking stays off: TBB's and
# Embree's worker pools outlive main.
#
# Cases that compare timings must not share the machine with other tests: where CAUSTICS_SERIAL_<program>
# holds a GoogleTest filter, the cases it matches are discovered apart and run alone (RUN_SERIAL).
find_package(GTest REQUIRED)
include(GoogleTest)
# ctest's time limit per case: 600 s, three times that under the sanitizers, whose instrumented code runs
# several times slower (wave_pde's drawn conformance cases took over 600 s there).
set(CAUSTICS_TEST_PROPERTIES TIMEOUT 600)
if(CAUSTICS_SANITIZE)
  set(CAUSTICS_TEST_PROPERTIES TIMEOUT 1800 ENVIRONMENT "ASAN_OPTIONS=halt_on_error=1:detect_leaks=0")
endif()

function(caustics_add_gtest source)
  get_filename_component(name ${source} NAME_WE)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN} caustics_testing GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE CAUSTICS_BINARY="$<TARGET_FILE:caustics>"
                             CAUSTICS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  add_dependencies(${name} caustics)
  if(DEFINED CAUSTICS_SERIAL_${name})
    gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} DISCOVERY_TIMEOUT 60
                         TEST_FILTER "-${CAUSTICS_SERIAL_${name}}" PROPERTIES ${CAUSTICS_TEST_PROPERTIES})
    gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} DISCOVERY_TIMEOUT 60
                         TEST_FILTER "${CAUSTICS_SERIAL_${name}}" PROPERTIES ${CAUSTICS_TEST_PROPERTIES} RUN_SERIAL TRUE)
  else()
    gtest_discover_tests(${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} DISCOVERY_TIMEOUT 60
                         PROPERTIES ${CAUSTICS_TEST_PROPERTIES})
  endif()
endfunction()
