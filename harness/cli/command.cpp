#include "command.hpp"

#include <algorithm>

#include "params.hpp"

namespace caustics::cli {
namespace {

// Function-local static: registrars run during static initialisation in an unspecified order.
std::vector<Command>& table() {
    static std::vector<Command> commands;
    return commands;
}

}  // namespace

CommandRegistrar::CommandRegistrar(Command (*make)()) { table().push_back(make()); }

std::vector<Command> registered_commands() {
    std::vector<Command> out = table();
    std::sort(out.begin(), out.end(), [](const Command& a, const Command& b) {
        return a.order != b.order ? a.order < b.order : a.name < b.name;
    });
    return out;
}

std::map<std::string, std::string> parse_assignments(const std::vector<std::string>& sets, const std::string& option) {
    std::map<std::string, std::string> out;
    for (const std::string& text : sets) {
        auto [key, value] = parse_assignment(text, option);
        out[key] = value;
    }
    return out;
}

void add_reference_sampling_options(CLI::App& app, SamplerKind& sampler, int& replicas, double& noise_target,
                                    std::uint64_t& photon_cap) {
    const std::map<std::string, SamplerKind> samplers{{"sobol", SamplerKind::Sobol}, {"independent", SamplerKind::Independent}};
    app.add_option("--sampler", sampler,
                   "Reference emission samples: sobol (Owen-scrambled Sobol' in replicas) or independent")
        ->transform(CLI::CheckedTransformer(samplers, CLI::ignore_case))
        ->default_str("sobol");
    app.add_option("--replicas", replicas, "Independent replicas of the reference (standard error from their spread)")
        ->check(CLI::Range(2, ReferenceSettings::kMaxReplicas))
        ->capture_default_str();
    app.add_option("--noise-target", noise_target,
                   "Add reference photons in rounds until its noise_nrmse is at most this (0: fixed --photons)")
        ->check(CLI::Range(0.0, 10.0))
        ->capture_default_str();
    app.add_option("--photon-cap", photon_cap, "Most photons a noise target may use (then reported as not met)")
        ->check(CLI::Range(std::uint64_t{1000}, std::uint64_t{100'000'000'000}))
        ->capture_default_str();
}

}  // namespace caustics::cli
