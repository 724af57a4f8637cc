// caustics sweep-worker: the worker process of a sweep (harness/sweep/worker.hpp), started by `caustics
// sweep` and not meant to be run by hand (hidden from --help). It reads one run a line from stdin, the
// arguments of `caustics render`, renders it in this process with the scene frame and reference of the
// previous run kept loaded (run/render_run.hpp, LoadedFrame), and answers with the exit status a
// `caustics render` process would have had.
#include <memory>
#include <string>
#include <vector>

#include "command.hpp"
#include "usage_errors.hpp"
#include <caustics/run/render_run.hpp>
#include <caustics/sweep/worker.hpp>
#include <caustics/util/errors.hpp>

namespace caustics::cli {
namespace {

int report(const std::string& message, int code) {
    std::cerr << "caustics: error: " << message << "\n";
    return code;
}

const Command& render_command() {
    static const Command command = [] {
        for (const Command& c : registered_commands())
            if (c.name == "render") return c;
        throw std::logic_error("sweep-worker: no render command is registered");
    }();
    return command;
}

// One run: `argv` parsed by a fresh `render` command exactly as main() parses a `caustics render` command
// line, and its errors reported in main()'s words and exit codes (2 bad input, 1 internal failure).
int render_one(const std::vector<std::string>& argv) {
    try {
        CLI::App app{"", "caustics"};
        app.require_subcommand(1, 1);
        const Command& command = render_command();
        CLI::App* sub = app.add_subcommand(command.name, command.summary);
        const std::function<int()> action = command.setup(*sub);
        std::vector<const char*> args = {"caustics"};
        for (const std::string& a : argv) args.push_back(a.c_str());
        try {
            app.parse(static_cast<int>(args.size()), args.data());
        } catch (const CLI::ParseError& e) {
            if (auto unknown = unknown_argument_message(app)) return report(*unknown, 2);
            return report(usage_error_message(app, e), 2);
        } catch (const InputError&) {
            if (auto unknown = unknown_argument_message(app)) return report(*unknown, 2);
            throw;
        }
        if (!sub->parsed()) return report("sweep-worker: the request is not a render command line", 2);
        return action();
    } catch (const InputError& e) {
        return report(e.what(), 2);
    } catch (const std::exception& e) {
        return report(std::string("internal failure: ") + e.what(), 1);
    } catch (...) {
        return report("internal failure: unknown exception", 1);
    }
}

Command make_sweep_worker_command() {
    Command c;
    c.name = "sweep-worker";
    c.summary = "The worker process of `caustics sweep` (started by it; reads runs from stdin)";
    c.order = 1000;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        app.group("");   // hidden from --help
        return []() {
            LoadedFrame kept;
            keep_loaded_frame(&kept);
            const int code = serve_sweep_worker(render_one);
            keep_loaded_frame(nullptr);
            return code;
        };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_sweep_worker_command);

}  // namespace caustics::cli
