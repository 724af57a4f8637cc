#pragma once
// The context block every result carries (Google Benchmark's `context`, nvbench's device section):
// host, CPU, cores, threads, build type, compiler, project commit and library versions.
#include <nlohmann/json.hpp>

namespace caustics {

nlohmann::json run_context();

}  // namespace caustics
