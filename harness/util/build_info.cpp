#include <caustics/util/build_info.hpp>

#ifndef CAUSTICS_BUILD_TYPE
#define CAUSTICS_BUILD_TYPE "unknown"
#endif
#ifndef CAUSTICS_VERSION
#define CAUSTICS_VERSION "unknown"
#endif

namespace caustics {

const char* build_type() { return CAUSTICS_BUILD_TYPE; }
const char* project_version() { return CAUSTICS_VERSION; }

}  // namespace caustics
