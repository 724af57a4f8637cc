// caustics sweep-worker: the worker process of a sweep (harness/sweep/worker.hpp), started by `caustics
// sweep` and not meant to be run by hand (hidden from --help). It reads one run a line from stdin, the
// arguments of `caustics render`, renders it in this process with the scene frame and reference of the
// previous run kept loaded (run/render_run.hpp, LoadedFrame), and answers with the exit status a
// `caustics render` process would have had.
#include <memory>
#include <string>
#include <vector>

#include "command.hpp"
#include "dispatch.hpp"
#include "options.hpp"
#include "render_command.hpp"
#include <caustics/run/render_run.hpp>
#include <caustics/sweep/worker.hpp>
#include <caustics/util/errors.hpp>

namespace caustics::cli {
namespace {

// One run: `argv` parsed by a fresh `render` command exactly as main() parses a `caustics render` command
// line (dispatch.hpp: the same error lines and exit codes, 2 bad input, 1 internal failure). The options'
// "valid" texts are forgotten with the parser, whose options they are keyed by.
int render_one(const std::vector<std::string>& argv, LoadedFrame* kept) {
    struct ForgetValidTexts {
        ~ForgetValidTexts() { forget_valid_texts(); }
    } forget;   // destroyed after the parser below
    try {
        CLI::App app{"", "caustics"};
        app.require_subcommand(1, 1);
        CLI::App* sub = app.add_subcommand(kRenderName, kRenderSummary);
        const std::vector<ParsedCommand> commands = {{sub, setup_render(*sub, kept)}};
        std::vector<const char*> args = {"caustics"};
        for (const std::string& a : argv) args.push_back(a.c_str());
        return parse_and_run(app, commands, static_cast<int>(args.size()), args.data());
    } catch (const InputError& e) {   // setting the command up
        return report_error(e.what(), 2);
    } catch (const std::exception& e) {
        return report_error(std::string("internal failure: ") + e.what(), 1);
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
            return serve_sweep_worker([&kept](const std::vector<std::string>& argv) { return render_one(argv, &kept); });
        };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_sweep_worker_command);

}  // namespace caustics::cli
