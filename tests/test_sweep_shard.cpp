// Sharded sweeps (harness/sweep/shard.hpp, slurm.hpp): the cost-balanced assignment, the shard option's
// validation, a sweep run whole against the same sweep run as 3 shards and merged (identical run ids,
// parameters and errors), the refusals of a merge (a missing shard, a shard of another spec, an
// unfinished shard) with exit code 2, merge idempotence, and the Slurm job scripts a dry run writes.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>
#include <sstream>

#include <caustics/sweep/shard.hpp>
#include <caustics/sweep/sweep_spec.hpp>
#include <caustics/util/errors.hpp>
#include "test_support.hpp"

using namespace caustics;
namespace fs = std::filesystem;

namespace {

struct TempDir {
    fs::path path;
    explicit TempDir(const std::string& name)
        : path(fs::temp_directory_path() / ("caustics_test_shard_" + name + "_" + std::to_string(getpid()))) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

std::string q(const fs::path& p) { return test_support::quote(p.string()); }

int run_program(const std::string& args, const fs::path& log) {
    const std::string command = std::string(CAUSTICS_BINARY) + " " + args + " >" + q(log) + " 2>&1";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<nlohmann::json> rows_of(const fs::path& jsonl) {
    std::vector<nlohmann::json> rows;
    std::ifstream in(jsonl);
    for (std::string line; std::getline(in, line);) rows.push_back(nlohmann::json::parse(line));
    return rows;
}

PlannedRun run_with(const std::string& id, int grid, int iterations) {
    PlannedRun r;
    r.id = id;
    r.params = {{"grid", std::to_string(grid)}, {"iterations", std::to_string(iterations)}};
    return r;
}

// Two methods on two scenes, ten runs: enough for three shards of unequal cost.
const char* kSpec = R"({
  "scenes": ["sine", "flat_oblique"],
  "reference": {"photons": 20000, "replicas": 4},
  "timing": {"warmup": 0, "repeats": 1, "max_time_s": 0.2},
  "methods": {"caustic_triangles": {"grid": [16, 32, 64]}, "caustic_mapping": {"grid": [32], "iterations": [1, 2]}}
})";

}  // namespace

TEST(SweepShard, AssignmentCoversEveryRunOnceAndBalancesCost) {
    std::vector<PlannedRun> runs;
    // A plan whose expensive runs all come last: a split by position would give one shard all of them.
    for (int i = 0; i < 12; ++i) runs.push_back(run_with("small" + std::to_string(i), 16, 1));
    for (int i = 0; i < 4; ++i) runs.push_back(run_with("large" + std::to_string(i), 256, 2));
    const auto shards = assign_shards(runs, 4);
    ASSERT_EQ(shards.size(), 4u);
    std::vector<int> seen(runs.size(), 0);
    double most = 0.0, least = 1e300, largest_run = 0.0;
    for (const auto& shard : shards) {
        EXPECT_TRUE(std::is_sorted(shard.begin(), shard.end()));
        double load = 0.0;
        for (const std::size_t p : shard) {
            ++seen[p];
            load += estimated_run_cost(runs[p]);
            largest_run = std::max(largest_run, estimated_run_cost(runs[p]));
        }
        most = std::max(most, load);
        least = std::min(least, load);
    }
    for (const int s : seen) EXPECT_EQ(s, 1);
    // Greedy by decreasing cost: no shard exceeds another by more than one run's cost; here each shard
    // gets exactly one large run and three small ones.
    EXPECT_LE(most - least, largest_run);
    for (const auto& shard : shards) EXPECT_EQ(shard.size(), 4u);
    EXPECT_EQ(assign_shards(runs, 4), shards);   // the same plan, the same assignment
    EXPECT_DOUBLE_EQ(estimated_run_cost(runs.back()), 256.0 * 256.0 * 2.0);
}

TEST(SweepShard, ShardOptionIsValidated) {
    EXPECT_EQ(parse_shard("2/5").index, 2);
    EXPECT_EQ(parse_shard("2/5").count, 5);
    for (const char* bad : {"5/5", "1", "a/3", "-1/3", "0/0", "1/100001", "1/3/4", ""}) {
        try {
            parse_shard(bad);
            ADD_FAILURE() << "accepted " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("--shard"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("0 <= I < N"), std::string::npos) << e.what();
        }
    }
}

TEST(SweepShard, MergedShardsEqualTheWholeSweepAndMergeIsRefusedWhenIncomplete) {
    const TempDir d("merge");
    const fs::path spec = d.path / "small.json";
    std::ofstream(spec) << kSpec;
    const std::string cache = " --cache " + q(d.path / "cache");
    const fs::path whole = d.path / "whole", sharded = d.path / "sharded";
    ASSERT_EQ(run_program("sweep " + q(spec) + " --out " + q(whole) + cache, d.path / "log"), 0)
        << test_support::slurp(d.path / "log");
    ASSERT_EQ(run_program("sweep " + q(spec) + " --out " + q(sharded) + " --references-only" + cache, d.path / "log"), 0)
        << test_support::slurp(d.path / "log");
    EXPECT_TRUE(fs::exists(sharded / "references" / "sine-f0" / "reference.json"));
    EXPECT_TRUE(fs::exists(sharded / "references" / "flat_oblique-f0" / "reference.json"));
    for (int i : {0, 2}) {
        ASSERT_EQ(run_program("sweep " + q(spec) + " --out " + q(sharded) + " --shard " + std::to_string(i) + "/3" + cache,
                              d.path / "log"), 0)
            << test_support::slurp(d.path / "log");
    }
    // Shard 1 has not run: the merge names it, exits 2 and writes nothing.
    EXPECT_EQ(run_program("sweep merge " + q(sharded), d.path / "log"), 2);
    EXPECT_NE(test_support::slurp(d.path / "log").find("1 of 3 shards are missing: 1"), std::string::npos)
        << test_support::slurp(d.path / "log");
    EXPECT_FALSE(fs::exists(sharded / "results.jsonl"));
    ASSERT_EQ(run_program("sweep " + q(spec) + " --out " + q(sharded) + " --shard 1/3" + cache, d.path / "log"), 0);
    ASSERT_EQ(run_program("sweep merge " + q(sharded), d.path / "log"), 0) << test_support::slurp(d.path / "log");
    const std::string first_csv = test_support::slurp(sharded / "results.csv");
    const std::string first_jsonl = test_support::slurp(sharded / "results.jsonl");
    ASSERT_EQ(run_program("sweep merge " + q(sharded), d.path / "log"), 0);
    EXPECT_EQ(test_support::slurp(sharded / "results.csv"), first_csv);     // idempotent
    EXPECT_EQ(test_support::slurp(sharded / "results.jsonl"), first_jsonl);

    const auto a = rows_of(whole / "results.jsonl"), b = rows_of(sharded / "results.jsonl");
    ASSERT_EQ(a.size(), 10u);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i]["run_id"], b[i]["run_id"]);
        EXPECT_EQ(a[i]["params"], b[i]["params"]);
        EXPECT_EQ(a[i]["status"], b[i]["status"]);
        EXPECT_EQ(a[i]["error"], b[i]["error"]) << a[i]["run_id"];   // the same references, the same bits
        EXPECT_EQ(a[i]["reference"]["cache_key"], b[i]["reference"]["cache_key"]);
    }
    // The same CSV header, and the runs' files reachable where the report looks for them.
    EXPECT_EQ(first_csv.substr(0, first_csv.find('\n')), test_support::slurp(whole / "results.csv").substr(0, first_csv.find('\n')));
    EXPECT_TRUE(fs::exists(sharded / "runs" / b[0]["run_id"].get<std::string>() / "receiver.exr"));
    const nlohmann::json manifest = nlohmann::json::parse(test_support::slurp(sharded / "manifest.json"));
    ASSERT_EQ(manifest["shards"].size(), 3u);
    EXPECT_TRUE(manifest["shards"][0]["host"].contains("name"));
    EXPECT_EQ(manifest["runs_planned"], 10);
    ASSERT_EQ(run_program("report " + q(sharded), d.path / "log"), 0) << test_support::slurp(d.path / "log");

    // A shard of another spec (another grid) in the folder: refused, naming what differs.
    const fs::path other = d.path / "other.json";
    std::string text = kSpec;
    text.replace(text.find("[16, 32, 64]"), 12, "[16, 32, 48]");
    std::ofstream(other) << text;
    fs::remove_all(sharded / "shards" / "1");
    ASSERT_EQ(run_program("sweep " + q(other) + " --out " + q(sharded) + " --shard 1/3" + cache, d.path / "log"), 0);
    EXPECT_EQ(run_program("sweep merge " + q(sharded), d.path / "log"), 2);
    EXPECT_NE(test_support::slurp(d.path / "log").find("ran another plan"), std::string::npos) << test_support::slurp(d.path / "log");
    EXPECT_NE(test_support::slurp(d.path / "log").find("methods.caustic_triangles.grid"), std::string::npos);
    // Resuming a shard folder with another shard count is refused; with its own it has nothing left to do.
    EXPECT_EQ(run_program("sweep " + q(spec) + " --out " + q(sharded) + " --shard 0/4 --resume" + cache, d.path / "log"), 2);
    EXPECT_NE(test_support::slurp(d.path / "log").find("started as shard 0/3"), std::string::npos)
        << test_support::slurp(d.path / "log");
    EXPECT_EQ(run_program("sweep " + q(spec) + " --out " + q(sharded) + " --shard 0/3 --resume" + cache, d.path / "log"), 0);
}

TEST(SweepShard, SlurmDryRunWritesTheThreeJobScripts) {
    const TempDir d("slurm");
    const fs::path spec = d.path / "small.json";
    std::ofstream(spec) << kSpec;
    const fs::path out = d.path / "out";
    ASSERT_EQ(run_program("sweep " + q(spec) + " --out " + q(out) + " --slurm 3 --threads 2 --dry-run --cache " + q(d.path / "c"),
                          d.path / "log"), 0)
        << test_support::slurp(d.path / "log");
    const std::string refs = test_support::slurp(out / "slurm" / "references.sbatch");
    const std::string runs = test_support::slurp(out / "slurm" / "runs.sbatch");
    const std::string merge = test_support::slurp(out / "slurm" / "merge.sbatch");
    EXPECT_NE(refs.find("#SBATCH --array=0-1"), std::string::npos) << refs;   // 2 scene frames
    EXPECT_NE(refs.find("--references-only --shard \"${SLURM_ARRAY_TASK_ID}/2\""), std::string::npos) << refs;
    EXPECT_NE(runs.find("#SBATCH --array=0-2"), std::string::npos) << runs;
    EXPECT_NE(runs.find("#SBATCH --cpus-per-task=2"), std::string::npos) << runs;
    EXPECT_NE(runs.find("--shard \"${SLURM_ARRAY_TASK_ID}/3\""), std::string::npos) << runs;
    EXPECT_NE(runs.find(fs::absolute(spec).string()), std::string::npos) << runs;
    EXPECT_NE(merge.find("sweep merge"), std::string::npos) << merge;
    EXPECT_NE(merge.find(" report "), std::string::npos) << merge;
    EXPECT_NE(test_support::slurp(d.path / "log").find("nothing submitted"), std::string::npos);
    EXPECT_FALSE(fs::exists(out / "results.jsonl"));
}
