#include <caustics/sweep/shard.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include <caustics/sweep/sweep.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/image_io.hpp>

#include "detail/sweep_files.hpp"

namespace caustics {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool all_digits(const std::string& s) {
    return !s.empty() && s.size() <= 9 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// A number of the run's parameters (canonical text), or `fallback` when absent or not a number.
double param_number(const PlannedRun& run, const char* name, double fallback) {
    const auto it = run.params.find(name);
    if (it == run.params.end()) return fallback;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    return end && *end == '\0' && v > 0.0 ? v : fallback;
}

json read_json(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return json();
    json j = json::parse(in, nullptr, false);
    return j.is_discarded() ? json() : j;
}

InputError merge_error(const fs::path& where, const std::string& problem) {
    return InputError(where.string(), "", problem);
}

// What `sweep merge DIR` and `sweep status DIR` are given must be a folder: named, with what it should hold.
void check_sweep_folder(const std::string& dir_text, const std::string& command) {
    const std::string valid = "; valid: a sweep folder, the --out of `caustics sweep` (manifest.json and results, or "
                              "shards/0..N-1 of a sharded sweep)";
    if (dir_text.empty()) throw InputError(command, "DIR", "empty path" + valid);
    std::error_code ec;
    const fs::file_status st = fs::status(dir_text, ec);
    if (!fs::exists(st)) throw InputError(dir_text, "", "does not exist" + valid);
    if (!fs::is_directory(st)) throw InputError(dir_text, "", "is not a folder" + valid);
}

struct Shard {
    int index = -1;
    fs::path dir;
    json manifest;
    std::vector<std::size_t> positions;
    std::vector<std::string> run_ids;
};

// Every shard folder's manifest, checked against each other (see merge_shards); throws before anything
// is written.
std::vector<Shard> read_shards(const fs::path& dir) {
    const fs::path root = dir / "shards";
    std::error_code ec;
    if (!fs::is_directory(root, ec))
        throw merge_error(dir, "holds no shards/ folder; run `caustics sweep SPEC --out " + dir.string() +
                                   " --shard I/N` for every I in 0..N-1 first");
    std::vector<Shard> shards;
    for (const auto& entry : fs::directory_iterator(root)) {
        const std::string name = entry.path().filename().string();
        if (!entry.is_directory() || !all_digits(name))
            throw merge_error(entry.path(), "is not a shard folder (shards/ holds folders named 0..N-1 only)");
        Shard s;
        s.index = std::stoi(name);
        s.dir = entry.path();
        s.manifest = read_json(s.dir / "manifest.json");
        const json& record = s.manifest.is_object() ? s.manifest.value("shard", json()) : json();
        if (!record.is_object() || !record.contains("positions") || !record.contains("run_ids") ||
            record.value("index", -1) != s.index)
            throw merge_error(s.dir / "manifest.json",
                              "is missing, unreadable or not the manifest of shard " + name +
                                  " (its `shard` record); rerun that shard with --shard " + name + "/N --resume");
        s.positions = record["positions"].get<std::vector<std::size_t>>();
        s.run_ids = record["run_ids"].get<std::vector<std::string>>();
        if (s.positions.size() != s.run_ids.size())
            throw merge_error(s.dir / "manifest.json", "its shard record lists " + std::to_string(s.positions.size()) +
                                                           " positions for " + std::to_string(s.run_ids.size()) + " runs");
        shards.push_back(std::move(s));
    }
    if (shards.empty()) throw merge_error(root, "holds no shard folder; nothing to merge");
    std::sort(shards.begin(), shards.end(), [](const Shard& a, const Shard& b) { return a.index < b.index; });
    const Shard& first = shards.front();
    const int count = first.manifest["shard"].value("count", 0);
    std::vector<std::string> problems;
    for (const Shard& s : shards) {
        const int c = s.manifest["shard"].value("count", 0);
        if (c != count)
            problems.push_back("shard " + std::to_string(s.index) + " is one of " + std::to_string(c) + ", shard " +
                               std::to_string(first.index) + " one of " + std::to_string(count));
        if (s.manifest.value("plan_hash", json()) != first.manifest.value("plan_hash", json())) {
            std::vector<std::string> diff;
            sweep_files::differences(first.manifest.value("plan", json()), s.manifest.value("plan", json()), "", diff,
                                     "in shard " + std::to_string(first.index), "in shard " + std::to_string(s.index));
            problems.push_back("shard " + std::to_string(s.index) + " ran another plan (" +
                               (diff.empty() ? std::string("plan_hash differs") : sweep_files::listed(diff)) + ")");
        }
    }
    if (!problems.empty())
        throw merge_error(root, "the shards are of different sweeps: " + sweep_files::listed(problems) +
                                    "; merge shards of one spec and one --shard count only");
    std::vector<std::string> missing;
    for (int i = 0; i < count; ++i)
        if (std::none_of(shards.begin(), shards.end(), [i](const Shard& s) { return s.index == i; }))
            missing.push_back(std::to_string(i));
    for (const Shard& s : shards)
        if (s.index >= count) problems.push_back(std::to_string(s.index));
    if (!missing.empty())
        throw merge_error(root, std::to_string(missing.size()) + " of " + std::to_string(count) +
                                    " shards are missing: " + sweep_files::listed(missing) +
                                    "; run them (--shard I/" + std::to_string(count) + ") before merging");
    if (!problems.empty())
        throw merge_error(root, "shard folders beyond 0.." + std::to_string(count - 1) + ": " + sweep_files::listed(problems));
    return shards;
}

// A relative symbolic link `link` -> `target`, replacing what is there (a merge run twice is the same).
void link_into(const fs::path& target, const fs::path& link) {
    std::error_code ec;
    fs::create_directories(link.parent_path());
    const fs::path relative = fs::relative(target, link.parent_path(), ec);
    if (fs::is_symlink(link, ec) && fs::read_symlink(link, ec) == relative) return;
    fs::remove_all(link, ec);
    fs::create_directory_symlink(relative, link);
}

}  // namespace

ShardId parse_shard(const std::string& text, const std::string& option) {
    const std::size_t slash = text.find('/');
    const std::string valid = "I/N with integers 0 <= I < N <= " + std::to_string(kMaxShards) + ", e.g. 0/4";
    if (slash == std::string::npos || !all_digits(text.substr(0, slash)) || !all_digits(text.substr(slash + 1)))
        throw invalid_value(option, "'" + text + "' is not I/N", valid);
    ShardId s;
    s.index = std::stoi(text.substr(0, slash));
    s.count = std::stoi(text.substr(slash + 1));
    if (s.count < 1 || s.count > kMaxShards || s.index >= s.count)
        throw invalid_value(option, "'" + text + "' names no shard", valid);
    return s;
}

double estimated_run_cost(const PlannedRun& run) {
    const double grid = param_number(run, "grid", 1.0);
    return grid * grid * std::max(1.0, param_number(run, "iterations", 1.0));
}

std::vector<std::vector<std::size_t>> assign_shards(const std::vector<PlannedRun>& runs, int count) {
    std::vector<std::size_t> order(runs.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::vector<double> cost(runs.size());
    for (std::size_t i = 0; i < runs.size(); ++i) cost[i] = estimated_run_cost(runs[i]);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
    std::vector<std::vector<std::size_t>> shards(static_cast<std::size_t>(std::max(1, count)));
    std::vector<double> load(shards.size(), 0.0);
    for (const std::size_t i : order) {
        const std::size_t s = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
        shards[s].push_back(i);
        load[s] += cost[i];
    }
    for (auto& s : shards) std::sort(s.begin(), s.end());
    return shards;
}

MergeSummary merge_shards(const std::string& dir_text) {
    check_sweep_folder(dir_text, "sweep merge");
    const fs::path dir(dir_text);
    const std::vector<Shard> shards = read_shards(dir);
    const json& plan = shards.front().manifest.value("plan", json());
    const std::size_t total = plan.is_object() ? plan["runs"].value("count", std::size_t{0}) : 0;

    // Every run of the plan exactly once, each with its result line.
    std::vector<std::string> lines(total);
    std::vector<int> owner(total, -1);
    std::vector<std::string> problems;
    for (const Shard& s : shards) {
        std::map<std::string, std::string> by_id;
        for (std::string& line : sweep_files::read_result_lines(s.dir / "results.jsonl")) {
            const std::string id = json::parse(line)["run_id"].get<std::string>();
            by_id[id] = std::move(line);
        }
        std::vector<std::string> unfinished;
        for (std::size_t k = 0; k < s.positions.size(); ++k) {
            const std::size_t p = s.positions[k];
            if (p >= total || owner[p] >= 0) {
                problems.push_back("run " + s.run_ids[k] + " of shard " + std::to_string(s.index) +
                                   (p >= total ? " lies outside the plan" : " is also in shard " + std::to_string(owner[p])));
                continue;
            }
            owner[p] = s.index;
            const auto it = by_id.find(s.run_ids[k]);
            if (it == by_id.end()) unfinished.push_back(s.run_ids[k]);
            else lines[p] = it->second;
        }
        if (!unfinished.empty())
            problems.push_back("shard " + std::to_string(s.index) + " has not finished " + std::to_string(unfinished.size()) +
                               " of its " + std::to_string(s.positions.size()) + " runs (" +
                               sweep_files::listed(unfinished) + "; resume it with --shard " + std::to_string(s.index) +
                               "/" + std::to_string(shards.size()) + " --resume)");
    }
    std::size_t unassigned = 0;
    for (const int o : owner) unassigned += o < 0;
    if (unassigned) problems.push_back(std::to_string(unassigned) + " runs of the plan are in no shard");
    if (!problems.empty()) throw merge_error(dir / "shards", "cannot merge: " + sweep_files::listed(problems));

    // Checked: now the files. Results first, the manifest last (its presence says the merge is whole).
    std::vector<json> rows;
    for (const std::string& l : lines) rows.push_back(json::parse(l));
    write_text_atomic((dir / "results.jsonl").string(), sweep_files::joined(lines));
    const std::set<std::string> params = shards.front().manifest.value("csv_params", std::set<std::string>{});
    write_text_atomic((dir / "results.csv").string(), results_csv(params, rows));
    for (std::size_t p = 0; p < total; ++p) {
        const std::string id = rows[p]["run_id"].get<std::string>();
        link_into(dir / "shards" / std::to_string(owner[p]) / "runs" / id, dir / "runs" / id);
    }
    std::error_code ec;
    for (const Shard& s : shards) {
        if (!fs::is_directory(s.dir / "references", ec)) continue;
        for (const auto& entry : fs::directory_iterator(s.dir / "references"))
            if (!fs::exists(dir / "references" / entry.path().filename(), ec))
                link_into(entry.path(), dir / "references" / entry.path().filename());
    }
    json manifest = shards.front().manifest;
    for (const char* key : {"shard", "resumed", "csv_params"}) manifest.erase(key);
    manifest["runs_planned"] = total;
    json list = json::array();
    for (const Shard& s : shards) {
        json entry = {{"index", s.index}, {"runs", s.positions.size()}};
        for (const char* key : {"host", "cpu", "cores", "threads", "started", "slurm", "run_mode", "resumed"})
            if (s.manifest.contains(key)) entry[key] = s.manifest[key];
        // The merged folder's run mode is the shards' where they agree, else only per shard.
        if (s.manifest.value("run_mode", json()) != manifest.value("run_mode", json())) manifest.erase("run_mode");
        list.push_back(entry);
    }
    manifest["shards"] = list;
    write_text_atomic((dir / "manifest.json").string(), manifest.dump(2) + "\n");
    return {static_cast<int>(shards.size()), total};
}

json slurm_environment() {
    json j = json::object();
    for (const char* name : {"SLURM_JOB_ID", "SLURM_ARRAY_JOB_ID", "SLURM_ARRAY_TASK_ID", "SLURMD_NODENAME",
                             "SLURM_CPUS_PER_TASK"})
        if (const char* v = std::getenv(name)) j[name] = v;
    return j.empty() ? json() : j;
}

std::string sweep_status(const std::string& dir_text) {
    check_sweep_folder(dir_text, "sweep status");
    const fs::path dir(dir_text);
    std::ostringstream out;
    std::error_code ec;
    auto status_of = [&](const fs::path& folder, std::size_t planned) {
        std::map<std::string, std::size_t> by_status;
        const auto lines = sweep_files::read_result_lines(folder / "results.jsonl");
        for (const std::string& l : lines) ++by_status[json::parse(l).value("status", std::string("?"))];
        std::string s = std::to_string(lines.size()) + "/" + std::to_string(planned) + " runs done";
        for (const auto& [k, v] : by_status) s += ", " + std::to_string(v) + " " + k;
        if (fs::exists(folder / "results.jsonl", ec)) {
            const auto age = fs::file_time_type::clock::now() - fs::last_write_time(folder / "results.jsonl", ec);
            s += "; last result " + std::to_string(std::chrono::duration_cast<std::chrono::seconds>(age).count()) + " s ago";
        }
        return std::make_pair(lines.size(), s);
    };
    std::size_t done = 0, planned = 0;
    if (fs::is_directory(dir / "shards", ec)) {
        std::vector<fs::path> folders;
        for (const auto& entry : fs::directory_iterator(dir / "shards")) folders.push_back(entry.path());
        // In shard order (0, 1, ..., 10), not the directory's.
        std::sort(folders.begin(), folders.end(), [](const fs::path& a, const fs::path& b) {
            const std::string x = a.filename().string(), y = b.filename().string();
            return x.size() != y.size() ? x.size() < y.size() : x < y;
        });
        for (const fs::path& folder : folders) {
            const json m = read_json(folder / "manifest.json");
            const std::size_t n = m.is_object() && m.contains("shard") ? m["shard"]["run_ids"].size() : 0;
            const auto [d, text] = status_of(folder, n);
            out << "shard " << folder.filename().string() << ": "
                << (m.is_object() ? text : std::string("not started")) << "\n";
            done += d;
            planned += n;
        }
    } else {
        const json m = read_json(dir / "manifest.json");
        if (!m.is_object())
            throw InputError(dir.string(), "", "holds no sweep (no manifest.json and no shards/ folder); valid: a sweep "
                                               "folder, the --out of `caustics sweep`");
        planned = m.value("runs_planned", std::size_t{0});
        const auto [d, text] = status_of(dir, planned);
        out << "sweep: " << text << "\n";
        done = d;
    }
    std::size_t references = 0;
    if (fs::is_directory(dir / "references", ec))
        for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "references")) ++references;
    out << "total: " << done << "/" << planned << " runs done; " << references << " references in "
        << (dir / "references").string() << (fs::exists(dir / "results.jsonl", ec) && fs::is_directory(dir / "shards", ec) ? "; merged" : "")
        << "\n";
    return out.str();
}

}  // namespace caustics
