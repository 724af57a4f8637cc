# caustics_add_method(NAME [LIBRARIES lib...]): the one call in a method folder's CMakeLists.txt, the same
# in this repository (methods/NAME/) and in a project outside it that found the installed package
# (find_package(caustics); examples/out_of_tree_method/). It takes every .cpp in the calling folder as
# the method's sources and every tests/test_*.cpp as one GoogleTest program.
#
# In this repository the sources form an object library (so the linker keeps the method's static
# registration object) that sees only the plugin contract and the building blocks (caustics::api,
# caustics::blocks): including the reference, a sweep or the report fails to compile. The `caustics`
# program and the test programs link it; the tests also link the framework and the shared test helpers.
#
# Outside it, the sources become a plugin: a MODULE library NAME.so in the build folder's plugins/ (for
# CAUSTICS_PLUGIN_PATH; installed to lib/caustics/plugins), compiled with CAUSTICS_PLUGIN and the entry
# point caustics_plugin_entry.cpp (api/plugin.hpp). It gets the include folders and definitions of
# caustics::api and caustics::blocks but links no harness library: the program that loads it has them.
# Its symbols are hidden but for the entry point, so plugins cannot clash with each other or the program.
# Its tests compile the same sources once more as built-in methods, linked with the installed framework
# (caustics::testing) and run with the installed data (CAUSTICS_SOURCE_DIR and CAUSTICS_DATA_DIR name
# PREFIX/share/caustics, whose scenes/ a test reads; CAUSTICS_BINARY is the installed program).
set(_CAUSTICS_METHOD_LIST_DIR ${CMAKE_CURRENT_LIST_DIR})

function(caustics_add_method name)
  cmake_parse_arguments(M "" "" "LIBRARIES" ${ARGN})
  if(TARGET method_${name})
    message(FATAL_ERROR "caustics_add_method(${name}) in ${CMAKE_CURRENT_SOURCE_DIR}: a method of that "
                        "name was already added from ${CAUSTICS_METHOD_DIR_${name}}")
  endif()
  set(CAUSTICS_METHOD_DIR_${name} ${CMAKE_CURRENT_SOURCE_DIR} CACHE INTERNAL "")
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  file(GLOB tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/tests/test_*.cpp)
  # Where the method's registration says it comes from (api/registry.hpp): its folder in the project.
  file(RELATIVE_PATH folder ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  if(folder)
    string(APPEND folder "/")
  endif()
  set(origin CAUSTICS_METHOD_DIR="${folder}")
  get_target_property(installed caustics::api IMPORTED)
  if(NOT installed)
    add_library(method_${name} OBJECT ${sources})
    target_link_libraries(method_${name} PUBLIC caustics::api caustics::blocks ${M_LIBRARIES})
    target_compile_definitions(method_${name} PRIVATE ${origin})
    set_target_properties(method_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    set_property(GLOBAL APPEND PROPERTY CAUSTICS_METHOD_TARGETS method_${name})
    if(CAUSTICS_BUILD_TESTS)
      foreach(test IN LISTS tests)
        caustics_add_gtest(${test} method_${name})
      endforeach()
    endif()
    return()
  endif()

  set(entry ${CMAKE_CURRENT_BINARY_DIR}/caustics_plugin_entry_${name}.cpp)
  configure_file(${_CAUSTICS_METHOD_LIST_DIR}/caustics_plugin_entry.cpp ${entry} COPYONLY)
  add_library(method_${name} OBJECT ${sources} ${entry})
  target_link_libraries(method_${name} PUBLIC caustics::api caustics::blocks)
  target_compile_definitions(method_${name} PRIVATE ${origin} CAUSTICS_PLUGIN CAUSTICS_SDK_VERSION="${caustics_VERSION}"
                             CAUSTICS_PLUGIN_BUILD_TYPE="$<IF:$<BOOL:$<CONFIG>>,$<CONFIG>,none>")
  set_target_properties(method_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON CXX_VISIBILITY_PRESET hidden
                        VISIBILITY_INLINES_HIDDEN ON)
  add_library(caustics_plugin_${name} MODULE $<TARGET_OBJECTS:method_${name}>)
  target_link_libraries(caustics_plugin_${name} PRIVATE ${M_LIBRARIES})
  set_target_properties(caustics_plugin_${name} PROPERTIES PREFIX "" OUTPUT_NAME ${name} LINKER_LANGUAGE CXX
                        LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/plugins)
  install(TARGETS caustics_plugin_${name} LIBRARY DESTINATION lib/caustics/plugins)

  if(NOT tests)
    return()
  endif()
  find_package(GTest REQUIRED)
  include(GoogleTest)
  enable_testing()
  add_library(method_${name}_builtin OBJECT ${sources})
  target_link_libraries(method_${name}_builtin PUBLIC caustics::testing ${M_LIBRARIES})
  target_compile_definitions(method_${name}_builtin PRIVATE ${origin})
  foreach(test IN LISTS tests)
    get_filename_component(test_name ${test} NAME_WE)
    add_executable(${test_name} ${test})
    target_link_libraries(${test_name} PRIVATE method_${name}_builtin caustics::testing GTest::gtest_main)
    target_compile_definitions(${test_name} PRIVATE CAUSTICS_SOURCE_DIR="${CAUSTICS_DATA_DIR}"
                               CAUSTICS_BINARY="$<TARGET_FILE:caustics::caustics>")
    # Two properties of one value each: gtest_discover_tests splits a list value. The time limit is
    # tripled in the project's sanitized build (instrumented code runs several times slower).
    set(timeout 600)
    if(CAUSTICS_SANITIZE)
      set(timeout 1800)
    endif()
    gtest_discover_tests(${test_name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT ${timeout}
                         ENVIRONMENT "CAUSTICS_DATA_DIR=${CAUSTICS_DATA_DIR}"
                         ENVIRONMENT_MODIFICATION "CAUSTICS_PLUGIN_PATH=path_list_prepend:${CMAKE_BINARY_DIR}/plugins")
  endforeach()
endfunction()
