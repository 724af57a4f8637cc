#include <caustics/view/record.hpp>

#include <filesystem>
#include <memory>
#include <stdexcept>

#include <unistd.h>

#include <OpenImageIO/imageio.h>

namespace caustics::view {
namespace {

std::string shell_quote(const std::string& s) {
    if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.=/:+,") == std::string::npos)
        return s;
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

}  // namespace

std::string render_command_line(const Session& s) {
    std::string cmd = "caustics render " + shell_quote(s.scene_argument()) + " --method " + s.method_name();
    const auto overrides = s.params().overrides();
    for (const ParamSpec& spec : s.params().info().params)
        if (auto it = overrides.find(spec.name); it != overrides.end())
            cmd += " --set " + shell_quote(spec.name + "=" + it->second);
    cmd += " --frame " + std::to_string(s.frame());
    cmd += " --photons " + std::to_string(s.options().progressive.reference.photons);
    return cmd;
}

nlohmann::json sweep_fragment(const Session& s) {
    nlohmann::json params = nlohmann::json::object();
    const MethodInfo& info = s.params().info();
    for (const ParamSpec& spec : info.params)
        params[spec.name] = nlohmann::json::array({param_json(info.name, spec, s.params().params().values().at(spec.name))});
    return {{"scenes", nlohmann::json::array({{{"scene", s.scene_argument()}, {"frames", {s.frame()}}}})},
            {"reference", {{"photons", s.options().progressive.reference.photons}}},
            {"methods", {{info.name, params}}}};
}

void write_rgba8_png(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgba) {
    if (width <= 0 || height <= 0 || rgba.size() != static_cast<std::size_t>(width) * height * 4)
        throw std::runtime_error("write_rgba8_png: " + path + ": the pixels do not match the size");
    const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + ".png";
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(tmp);
    if (!out) throw std::runtime_error("cannot write " + path + ": " + OIIO::geterror());
    const OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
    if (!out->open(tmp, spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgba.data()) || !out->close()) {
        const std::string why = out->geterror();
        std::filesystem::remove(tmp);
        throw std::runtime_error("cannot write " + path + ": " + why);
    }
    std::filesystem::rename(tmp, path);
}

}  // namespace caustics::view
