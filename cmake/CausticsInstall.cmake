# The data folder and the installed package.
#
# The data folder (util/resources.hpp) holds scenes/, scripts/ (report/ and sweeps/ are what the program
# reads) and build.json. The program finds it as share/caustics beside its own bin/ folder, so the build
# folder is laid out like an installation: bin/caustics, and share/caustics whose scenes/ and scripts/
# link to the source tree (edits show at once) and whose build.json names the source tree (for the git
# commit a run records).
#
# `cmake --install BUILD --prefix PREFIX` installs
#   bin/caustics                      the program, which loads method plugins (CAUSTICS_PLUGIN_PATH)
#   include/caustics/LAYER/           the public headers of each layer (not detail/), and
#   include/caustics/testing/         the test helpers of tests/ (for methods' tests)
#   lib/libcaustics_LAYER.a           the layers
#   lib/cmake/caustics/               caustics-config.cmake: targets caustics::LAYER, caustics::framework
#                                     (every layer), caustics::testing (framework + test helpers),
#                                     caustics::caustics (the program), and caustics_add_method()
#   share/caustics/                   scenes/, scripts/report/, scripts/sweeps/, build.json (version, and
#                                     the git commit of the last build)
include(CMakePackageConfigHelpers)

set(CAUSTICS_BUILD_DATA_DIR ${PROJECT_BINARY_DIR}/share/caustics)
file(MAKE_DIRECTORY ${CAUSTICS_BUILD_DATA_DIR})
foreach(folder scenes scripts)
  file(REMOVE ${CAUSTICS_BUILD_DATA_DIR}/${folder})
  file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${folder} ${CAUSTICS_BUILD_DATA_DIR}/${folder} SYMBOLIC)
endforeach()

function(caustics_json_string out value)
  string(REPLACE "\\" "\\\\" value "${value}")
  string(REPLACE "\"" "\\\"" value "${value}")
  set(${out} "\"${value}\"" PARENT_SCOPE)
endfunction()
caustics_json_string(version_json "${PROJECT_VERSION}")
caustics_json_string(source_json "${PROJECT_SOURCE_DIR}")
file(CONFIGURE OUTPUT ${CAUSTICS_BUILD_DATA_DIR}/build.json
     CONTENT "{\"version\": ${version_json}, \"source_dir\": ${source_json}}\n")

# An installation cannot ask git: its build.json records the commit of the last build.
add_custom_target(caustics_build_info ALL
                  COMMAND ${CMAKE_COMMAND} -DSOURCE=${PROJECT_SOURCE_DIR} -DVERSION=${PROJECT_VERSION}
                          -DOUT=${PROJECT_BINARY_DIR}/package/build.json -P ${PROJECT_SOURCE_DIR}/cmake/CausticsBuildInfo.cmake
                  BYPRODUCTS ${PROJECT_BINARY_DIR}/package/build.json VERBATIM)

# The test helpers, as a target: in the build as tests/, installed as include/caustics/testing/.
add_library(caustics_testing INTERFACE)
target_include_directories(caustics_testing INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/tests>
                           $<INSTALL_INTERFACE:include/caustics/testing>)
target_link_libraries(caustics_testing INTERFACE caustics_framework)
set_target_properties(caustics_framework PROPERTIES EXPORT_NAME framework)
set_target_properties(caustics_testing PROPERTIES EXPORT_NAME testing)

get_property(layers GLOBAL PROPERTY CAUSTICS_LAYERS)
install(TARGETS ${layers} caustics_framework caustics_testing EXPORT caustics-targets ARCHIVE DESTINATION lib)
install(TARGETS caustics EXPORT caustics-targets RUNTIME DESTINATION bin)
foreach(target IN LISTS layers)
  string(REGEX REPLACE "^caustics_" "" layer ${target})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/harness/${layer}/ DESTINATION include/caustics/${layer}
          FILES_MATCHING PATTERN "*.hpp" PATTERN "detail" EXCLUDE)
endforeach()
file(GLOB test_helpers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/*.hpp)
install(FILES ${test_helpers} DESTINATION include/caustics/testing)

install(DIRECTORY ${PROJECT_SOURCE_DIR}/scenes/ DESTINATION share/caustics/scenes)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/scripts/report/ DESTINATION share/caustics/scripts/report
        PATTERN "tests" EXCLUDE PATTERN "__pycache__" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/scripts/sweeps/ DESTINATION share/caustics/scripts/sweeps)
# Written again at install time: an install after a partial build (one target, not `all`) must not
# miss it. It names the source tree's commit at install time (the build's own, unless the tree moved on).
install(CODE "execute_process(COMMAND \"${CMAKE_COMMAND}\" \"-DSOURCE=${PROJECT_SOURCE_DIR}\" \"-DVERSION=${PROJECT_VERSION}\"
                              \"-DOUT=${PROJECT_BINARY_DIR}/package/build.json\" -P \"${PROJECT_SOURCE_DIR}/cmake/CausticsBuildInfo.cmake\"
                              COMMAND_ERROR_IS_FATAL ANY)")
install(FILES ${PROJECT_BINARY_DIR}/package/build.json DESTINATION share/caustics)

install(EXPORT caustics-targets NAMESPACE caustics:: DESTINATION lib/cmake/caustics)
# A plugin runs inside the program it was built against, with that program's types: only the exact
# version will do (the program refuses any other, harness/cli/plugins.cpp).
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/caustics-config-version.cmake
                                 COMPATIBILITY ExactVersion)
install(FILES ${PROJECT_SOURCE_DIR}/cmake/caustics-config.cmake
        ${PROJECT_BINARY_DIR}/package/caustics-config-version.cmake
        ${PROJECT_SOURCE_DIR}/cmake/CausticsMethod.cmake ${PROJECT_SOURCE_DIR}/cmake/caustics_plugin_entry.cpp
        DESTINATION lib/cmake/caustics)
