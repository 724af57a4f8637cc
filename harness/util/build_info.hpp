#pragma once
// What build made this program, recorded in every metrics.json, reference.json and manifest: the one
// place the build's compile-time facts enter the code.
namespace caustics {

const char* build_type();        // CMAKE_BUILD_TYPE ("Release", ...) or "unknown"
const char* project_version();   // the project's version ("0.2.0")

}  // namespace caustics
