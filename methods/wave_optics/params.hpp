#pragma once
// wave_optics' name, description and parameter table (the method is in wave_optics.cpp).
#include <string>
#include <vector>

#include <caustics/api/params.hpp>

namespace caustics::wave_optics {

inline constexpr const char* kName = "wave_optics";
extern const char* const kDoc;

std::vector<ParamSpec> param_table();

// The message for a grid that is not a product of 2, 3, 5 and 7, with the nearest valid sizes.
std::string fast_size_hint(long long grid);

}  // namespace caustics::wave_optics
