# caustics_add_method(NAME): the one call in methods/NAME/CMakeLists.txt.
#
# Compiles every .cpp in the method's folder into an object library (so the linker keeps the method's
# static registration object) that sees only the plugin contract and the building blocks
# (caustics::api, caustics::blocks): including the reference, a sweep or the report fails to compile.
# Every tests/test_*.cpp beside it becomes one GoogleTest program that links the method, the framework
# and the shared test helpers (tests/), discovered by ctest like the framework's own tests.
function(caustics_add_method name)
  cmake_parse_arguments(M "" "" "LIBRARIES" ${ARGN})
  if(TARGET method_${name})
    message(FATAL_ERROR "caustics_add_method(${name}) in ${CMAKE_CURRENT_SOURCE_DIR}: a method of that "
                        "name was already added from ${CAUSTICS_METHOD_DIR_${name}}")
  endif()
  set(CAUSTICS_METHOD_DIR_${name} ${CMAKE_CURRENT_SOURCE_DIR} CACHE INTERNAL "")
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  add_library(method_${name} OBJECT ${sources})
  target_link_libraries(method_${name} PUBLIC caustics::api caustics::blocks ${M_LIBRARIES})
  set_target_properties(method_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  set_property(GLOBAL APPEND PROPERTY CAUSTICS_METHOD_TARGETS method_${name})
  if(CAUSTICS_BUILD_TESTS)
    file(GLOB tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/tests/test_*.cpp)
    foreach(test IN LISTS tests)
      caustics_add_gtest(${test} method_${name})
    endforeach()
  endif()
endfunction()
