// caustics report DIR: figures, tables and report.md of a sweep folder (scripts/report/report.py).
#include <memory>

#include "command.hpp"
#include <caustics/report/report_front.hpp>

namespace caustics::cli {
namespace {

Command make_report_command() {
    Command c;
    c.name = "report";
    c.summary = "Write DIR/report.md, DIR/figures/*.png|pdf and DIR/tables/*.tex|md from a sweep folder";
    c.order = 50;
    c.setup = [](CLI::App& app) -> std::function<int()> {
        auto dir = std::make_shared<std::string>();
        app.add_option("dir", *dir, "Sweep output folder (holds results.csv)")->required();
        return [dir]() { return run_report(*dir); };
    };
    return c;
}

}  // namespace

CAUSTICS_REGISTER_COMMAND(make_report_command);
}  // namespace caustics::cli
