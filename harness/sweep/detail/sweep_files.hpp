#pragma once
// What the sweep runner and the shard merge share about a sweep folder's files.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace caustics::sweep_files {

// The complete lines of results.jsonl. A line cut off by a kill (no newline, or not JSON) is dropped:
// its run is redone.
std::vector<std::string> read_result_lines(const std::filesystem::path& path);

// The lines, each ended by a newline.
std::string joined(const std::vector<std::string>& lines);

// "key.path: <was> <was_name>, <now> <now_name>" for every leaf that differs between two JSON documents.
void differences(const nlohmann::json& was, const nlohmann::json& now, const std::string& path,
                 std::vector<std::string>& out, const std::string& was_name = "in the folder",
                 const std::string& now_name = "now");

// The first three items joined by "; ", then "and K more".
std::string listed(const std::vector<std::string>& items);

}  // namespace caustics::sweep_files
