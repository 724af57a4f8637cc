#include "detail/sweep_files.hpp"

#include <fstream>
#include <set>
#include <sstream>

namespace caustics::sweep_files {

namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::string> read_result_lines(const fs::path& path) {
    std::vector<std::string> lines;
    std::ifstream in(path, std::ios::binary);
    if (!in) return lines;
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();
    std::size_t begin = 0;
    while (true) {
        const std::size_t end = text.find('\n', begin);
        if (end == std::string::npos) break;
        std::string line = text.substr(begin, end - begin);
        begin = end + 1;
        const json row = json::parse(line, nullptr, false);
        if (!row.is_discarded() && row.is_object() && row.contains("run_id")) lines.push_back(std::move(line));
    }
    return lines;
}

std::string joined(const std::vector<std::string>& lines) {
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    return text;
}

namespace {

std::string brief(const json& v) {
    std::string s = v.dump();
    return s.size() > 80 ? s.substr(0, 77) + "..." : s;
}

}  // namespace

// "key.path: <in the folder> in the folder, <now> now" for every leaf that differs.
void differences(const json& was, const json& now, const std::string& path, std::vector<std::string>& out,
                 const std::string& was_name, const std::string& now_name) {
    if (was.is_object() && now.is_object()) {
        std::set<std::string> keys;
        for (const auto& [k, v] : was.items()) keys.insert(k);
        for (const auto& [k, v] : now.items()) keys.insert(k);
        for (const auto& k : keys) {
            const std::string sub = path.empty() ? k : path + "." + k;
            if (!was.contains(k)) out.push_back(sub + ": absent " + was_name + ", " + brief(now[k]) + " " + now_name);
            else if (!now.contains(k)) out.push_back(sub + ": " + brief(was[k]) + " " + was_name + ", absent " + now_name);
            else differences(was[k], now[k], sub, out, was_name, now_name);
        }
    } else if (was != now) {
        out.push_back((path.empty() ? std::string("plan") : path) + ": " + brief(was) + " " + was_name + ", " + brief(now) +
                      " " + now_name);
    }
}

std::string listed(const std::vector<std::string>& items) {
    std::string text;
    for (std::size_t i = 0; i < items.size() && i < 3; ++i) text += (i ? "; " : "") + items[i];
    if (items.size() > 3) text += "; and " + std::to_string(items.size() - 3) + " more";
    return text;
}

}  // namespace caustics::sweep_files
