#include "command.hpp"

#include <algorithm>
#include <cstdlib>

#include <caustics/util/errors.hpp>
#include <caustics/api/params.hpp>

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
    std::map<std::string, std::string> given;   // key -> its first assignment as written
    for (const std::string& text : sets) {
        auto [key, value] = parse_assignment(text, option);
        if (auto it = given.find(key); it != given.end())
            throw invalid_value(option, "'" + key + "' given twice (" + it->second + ", " + text + ")", "each KEY once");
        given[key] = text;
        out[key] = value;
    }
    return out;
}

CLI::Option* add_frame_option(CLI::App& app, int& frame) {
    return add_integer_option(app, "--frame", frame, 0, kMaxFrame, "Animation frame")->capture_default_str();
}

CLI::Option* add_threads_option(CLI::App& app, int& threads, const std::string& doc) {
    return add_integer_option(app, "--threads", threads, 0, kMaxThreads, doc, "0: every core");
}

CLI::Option* add_cache_option(CLI::App& app, std::string& cache_dir) {
    return add_output_folder_option(app, "--cache", cache_dir,
                                    "Reference cache folder (default $CAUSTICS_CACHE_DIR or results/cache)");
}

void add_reference_options(CLI::App& app, ReferenceSettings& s) {
    using RS = ReferenceSettings;
    add_integer_option(app, "--photons", s.photons, RS::kMinPhotons, RS::kMaxPhotons,
                       "Reference photons (the first round's with a noise target)")
        ->capture_default_str();
    add_integer_option(app, "--seed", s.seed, 0, RS::kMaxSeed, "Reference photon RNG seed")->capture_default_str();
    add_enum_option(app, "--sampler", s.sampler, {{"sobol", SamplerKind::Sobol}, {"independent", SamplerKind::Independent}},
                    "Reference emission samples: sobol (Owen-scrambled Sobol' in replicas) or independent")
        ->default_str("sobol");
    add_integer_option(app, "--replicas", s.replicas, RS::kMinReplicas, RS::kMaxReplicas,
                       "Independent replicas of the reference (standard error from their spread)")
        ->capture_default_str();
    add_number_option(app, "--noise-target", s.noise_target, 0.0, RS::kMaxNoiseTarget,
                      "Add reference photons in rounds until its noise_nrmse is at most this (0: fixed --photons)",
                      "0: fixed --photons")
        ->capture_default_str();
    // A cap below the first round's photons could never be met: refused when parsed. CLI11 checks the
    // options in the order they are declared, after --photons has taken its value.
    add_integer_option(app, "--photon-cap", s.photon_cap, RS::kMinPhotons, RS::kMaxPhotons,
                       "Most photons a noise target may use (then reported as not met); at least --photons")
        ->capture_default_str()
        ->check(CLI::Validator(
            [&s](std::string& text) -> std::string {
                const unsigned long long cap = std::strtoull(text.c_str(), nullptr, 10);
                if (cap < s.photons)
                    return text + " is below --photons " + std::to_string(s.photons) +
                           ": the cap must be at least the first round's photons";
                return {};
            },
            "at least --photons"));
}

}  // namespace caustics::cli
