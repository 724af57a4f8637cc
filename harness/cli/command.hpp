#pragma once
// Subcommands of the `caustics` program register themselves, like methods do: a new subcommand is a new
// harness/cli/commands_<name>.cpp with CAUSTICS_REGISTER_COMMAND(make_<name>_command); main.cpp names
// none of them.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "photon_sampler.hpp"
#include "reference.hpp"

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

// The reference's sampling options shared by `reference` and `render`: --sampler, --replicas,
// --noise-target, --photon-cap. Values are checked by CLI11 (exit 2 with the valid range).
void add_reference_sampling_options(CLI::App& app, SamplerKind& sampler, int& replicas, double& noise_target,
                                    std::uint64_t& photon_cap);

// --set KEY=VALUE assignments; throws InputError for one without '='. A repeated key keeps the last value.
std::map<std::string, std::string> parse_assignments(const std::vector<std::string>& sets, const std::string& option);

}  // namespace caustics::cli

#define CAUSTICS_CLI_CONCAT_INNER(a, b) a##b
#define CAUSTICS_CLI_CONCAT(a, b) CAUSTICS_CLI_CONCAT_INNER(a, b)
#define CAUSTICS_REGISTER_COMMAND(make_command)                                                 \
    static const ::caustics::cli::CommandRegistrar CAUSTICS_CLI_CONCAT(caustics_command_, __LINE__){make_command}
