# cmake -DSOURCE=DIR -DVERSION=V -DOUT=FILE -P CausticsBuildInfo.cmake: writes the build.json an
# installation carries (util/resources.hpp), with the source tree's commit at the time of the build.
# Run at every build; the file is rewritten only when its content changes.
find_package(Git QUIET)
set(commit "")
if(GIT_EXECUTABLE)
  execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SOURCE} rev-parse --short=12 HEAD
                  OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
endif()
file(CONFIGURE OUTPUT ${OUT} CONTENT "{\"version\": \"${VERSION}\", \"git_commit\": \"${commit}\"}\n")
