#pragma once
// The viewer's record actions: the current configuration as a reproducible run (a `caustics render`
// command line and a sweep-spec fragment, sweep/sweep_spec.hpp's format), and 8-bit RGBA images as PNG
// (the window's screenshot).
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/view/session.hpp>

namespace caustics::view {

// `caustics render SCENE --method NAME [--set K=V]... --frame F --photons N`: every parameter that
// differs from its default, in the table's order; arguments quoted for a POSIX shell where needed.
std::string render_command_line(const Session& s);

// {"scenes": [{"scene": SCENE, "frames": [F]}], "reference": {"photons": N},
//  "methods": {NAME: {PARAM: [VALUE], ...}}}: every parameter as a one-value axis, typed as the table
// says (api/params.hpp param_json), so that the sweep runs exactly this configuration.
nlohmann::json sweep_fragment(const Session& s);

// Writes width x height RGBA8 pixels (row 0 at the top) as a PNG, atomically (temporary name, rename).
void write_rgba8_png(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgba);

}  // namespace caustics::view
