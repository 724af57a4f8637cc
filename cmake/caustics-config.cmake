# find_package(caustics): the installed harness (cmake/CausticsInstall.cmake lists what it holds), for
# building methods outside its repository with caustics_add_method() (cmake/CausticsMethod.cmake).
# CAUSTICS_DATA_DIR is the installation's data folder (PREFIX/share/caustics).
include(CMakeFindDependencyMacro)
find_dependency(PkgConfig)
# Debian's exported OpenImageIO target names paths that need not exist: pkg-config instead.
if(NOT TARGET PkgConfig::OIIO)
  pkg_check_modules(OIIO QUIET IMPORTED_TARGET OpenImageIO)
endif()
if(NOT TARGET PkgConfig::FFTW)
  pkg_check_modules(FFTW QUIET IMPORTED_TARGET fftw3 fftw3f)
endif()
foreach(module OIIO FFTW)
  if(NOT TARGET PkgConfig::${module})
    set(caustics_FOUND FALSE)
    set(caustics_NOT_FOUND_MESSAGE "caustics needs ${module} through pkg-config (scripts/setup.sh installs it)")
    return()
  endif()
endforeach()
find_dependency(embree 3)
find_dependency(TBB)
find_dependency(TinyGLTF)
find_dependency(nlohmann_json)

# A plugin is timed inside an optimised program: unless the project chose a build type, build it
# optimised too (a single-configuration generator with no CMAKE_BUILD_TYPE compiles without -O).
# A plain variable in the calling scope: the project's cache is left as it is.
if(NOT CMAKE_CONFIGURATION_TYPES AND NOT CMAKE_BUILD_TYPE)
  set(CMAKE_BUILD_TYPE Release)
  message(STATUS "caustics: no CMAKE_BUILD_TYPE chosen, methods are built as Release")
endif()

include(${CMAKE_CURRENT_LIST_DIR}/caustics-targets.cmake)
get_filename_component(CAUSTICS_DATA_DIR ${CMAKE_CURRENT_LIST_DIR}/../../../share/caustics ABSOLUTE)
include(${CMAKE_CURRENT_LIST_DIR}/CausticsMethod.cmake)
