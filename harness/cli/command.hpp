#pragma once
// Subcommands of the `caustics` program register themselves, like methods do: a new subcommand is a new
// harness/cli/commands_<name>.cpp with CAUSTICS_REGISTER_COMMAND(make_<name>_command); main.cpp names
// none of them.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "options.hpp"
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/reference.hpp>

namespace caustics::cli {

// A subcommand: `setup` declares its options on its CLI11 sub-app and returns the action to run once
// the command line parsed. The action returns the exit code; it throws InputError for bad input.
struct Command {
    std::string name;
    std::string summary;
    int order = 100;   // position in --help
    std::function<std::function<int()>(CLI::App&)> setup;
};

// Sorted by order, then name.
std::vector<Command> registered_commands();

struct CommandRegistrar {
    explicit CommandRegistrar(Command (*make)());
};

// Ranges of the options that several commands share. The reference's come from ReferenceSettings, which
// the sweep spec's reference fields check against too, so that anything a command line asks for a sweep
// can ask for too.
inline constexpr std::int64_t kMinPhotons = ReferenceSettings::kMinPhotons;
inline constexpr std::int64_t kMaxPhotons = ReferenceSettings::kMaxPhotons;
inline constexpr std::int64_t kMaxSeed = ReferenceSettings::kMaxSeed;
inline constexpr std::int64_t kMaxFrame = 1'000'000;           // the scene's own frame count is checked on loading
inline constexpr std::int64_t kMaxThreads = 4096;
inline constexpr std::int64_t kMaxWarmup = 10'000;
inline constexpr std::int64_t kMaxRepeats = 100'000;

// --frame, --threads, --cache with the ranges above (options.hpp checks them).
CLI::Option* add_frame_option(CLI::App& app, int& frame);
CLI::Option* add_threads_option(CLI::App& app, int& threads, const std::string& doc);
CLI::Option* add_cache_option(CLI::App& app, std::string& cache_dir);

// The reference options shared by `reference` and `render`, bound to `settings`: --photons, --seed,
// --sampler, --replicas, --noise-target, --photon-cap (the arguments reference_arguments() writes),
// checked against ReferenceSettings' ranges as the sweep spec's reference fields are.
void add_reference_options(CLI::App& app, ReferenceSettings& settings);

// --set KEY=VALUE assignments; throws InputError for one without '=' or a KEY given twice.
std::map<std::string, std::string> parse_assignments(const std::vector<std::string>& sets, const std::string& option);

}  // namespace caustics::cli

#define CAUSTICS_CLI_CONCAT_INNER(a, b) a##b
#define CAUSTICS_CLI_CONCAT(a, b) CAUSTICS_CLI_CONCAT_INNER(a, b)
#define CAUSTICS_REGISTER_COMMAND(make_command)                                                 \
    static const ::caustics::cli::CommandRegistrar CAUSTICS_CLI_CONCAT(caustics_command_, __LINE__){make_command}
