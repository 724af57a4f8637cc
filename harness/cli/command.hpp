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

// Ranges of the options that several commands share. They follow the sweep spec's fields
// (harness/sweep_spec.cpp: reference.photons, reference.seed, frames, timing.warmup, timing.repeats), so
// that anything a command line asks for a sweep can ask for too.
inline constexpr std::int64_t kMinPhotons = 1000;
inline constexpr std::int64_t kMaxPhotons = 100'000'000'000;   // 1e11
inline constexpr std::int64_t kMaxSeed = std::int64_t{1} << 62;
inline constexpr std::int64_t kMaxFrame = 1'000'000;           // the scene's own frame count is checked on loading
inline constexpr std::int64_t kMaxThreads = 4096;
inline constexpr std::int64_t kMaxWarmup = 10'000;
inline constexpr std::int64_t kMaxRepeats = 100'000;

// --photons, --seed, --frame, --threads, --cache with the ranges above (options.hpp checks them).
CLI::Option* add_photons_option(CLI::App& app, std::uint64_t& photons, const std::string& doc);
CLI::Option* add_seed_option(CLI::App& app, std::uint64_t& seed, const std::string& doc);
CLI::Option* add_frame_option(CLI::App& app, int& frame);
CLI::Option* add_threads_option(CLI::App& app, int& threads, const std::string& doc);
CLI::Option* add_cache_option(CLI::App& app, std::string& cache_dir);

// The reference's sampling options shared by `reference` and `render`: --sampler, --replicas,
// --noise-target, --photon-cap, checked as the sweep spec's reference fields are.
void add_reference_sampling_options(CLI::App& app, SamplerKind& sampler, int& replicas, double& noise_target,
                                    std::uint64_t& photon_cap);

// --set KEY=VALUE assignments; throws InputError for one without '=' or a KEY given twice.
std::map<std::string, std::string> parse_assignments(const std::vector<std::string>& sets, const std::string& option);

}  // namespace caustics::cli

#define CAUSTICS_CLI_CONCAT_INNER(a, b) a##b
#define CAUSTICS_CLI_CONCAT(a, b) CAUSTICS_CLI_CONCAT_INNER(a, b)
#define CAUSTICS_REGISTER_COMMAND(make_command)                                                 \
    static const ::caustics::cli::CommandRegistrar CAUSTICS_CLI_CONCAT(caustics_command_, __LINE__){make_command}
