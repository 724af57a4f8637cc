#include <caustics/util/image_io.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include <OpenImageIO/imageio.h>

namespace caustics {
namespace {

namespace fs = std::filesystem;

// The temporary sibling of `path`, keeping the extension so OIIO picks the same format.
std::string temporary_name(const std::string& path) {
    fs::path p(path);
    std::string tmp = p.stem().string() + temporary_suffix() + p.extension().string();
    return (p.parent_path() / tmp).string();
}

void ensure_parent(const std::string& path) {
    fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) fs::create_directories(parent);
}

void commit(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot rename " + tmp + " to " + path);
    }
}

void write_oiio(const std::string& path, int w, int h, int c, OIIO::TypeDesc type, const void* data) {
    if (w <= 0 || h <= 0 || c <= 0) throw std::runtime_error("cannot write empty image " + path);
    ensure_parent(path);
    const std::string tmp = temporary_name(path);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw std::runtime_error("no image writer for " + path + ": " + OIIO::geterror());
    OIIO::ImageSpec spec(w, h, c, type);
    if (type == OIIO::TypeDesc::FLOAT) spec.attribute("compression", "zip");
    if (!out->open(tmp, spec)) throw std::runtime_error("cannot open " + tmp + ": " + out->geterror());
    bool ok = out->write_image(type, data);
    ok = out->close() && ok;
    if (!ok) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error("cannot write " + path + ": " + out->geterror());
    }
    commit(tmp, path);
}

float srgb_encode(float linear) {
    if (!(linear > 0.0f)) return 0.0f;   // also maps NaN to black
    if (linear >= 1.0f) return 1.0f;
    return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void write_exr(const Image& image, const std::string& path) {
    if (image.channels != 1 && image.channels != 3)
        throw std::runtime_error("write_exr: " + path + ": expected 1 or 3 channels");
    write_oiio(path, image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT, image.pixels.data());
}

Image read_image(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error("cannot read image " + path + ": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    Image image(spec.width, spec.height, spec.nchannels);
    bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data());
    in->close();
    if (!ok) throw std::runtime_error("cannot read image " + path + ": " + in->geterror());
    return image;
}

void write_png(const Image& linear, const std::string& path, double exposure) {
    const int c = linear.channels;
    if (c != 1 && c != 3) throw std::runtime_error("write_png: " + path + ": expected 1 or 3 channels");
    std::vector<std::uint8_t> bytes(linear.pixels.size());
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        float v = srgb_encode(static_cast<float>(linear.pixels[i] * exposure));
        bytes[i] = static_cast<std::uint8_t>(std::lround(v * 255.0f));
    }
    write_oiio(path, linear.width, linear.height, c, OIIO::TypeDesc::UINT8, bytes.data());
}

std::string temporary_suffix() {
    static const std::string suffix = [] {
        char host[256] = {};
        if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
        std::string h;
        for (const char* c = host; *c; ++c)
            h += (std::isalnum(static_cast<unsigned char>(*c)) || *c == '-') ? *c : '_';
        return ".tmp." + (h.empty() ? std::string("host") : h) + "." + std::to_string(::getpid());
    }();
    return suffix;
}

void write_text_atomic(const std::string& path, const std::string& text) {
    ensure_parent(path);
    const std::string tmp = path + temporary_suffix();
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno));
        out << text;
        out.flush();
        if (!out) {
            out.close();
            std::error_code ec;
            fs::remove(tmp, ec);
            throw std::runtime_error("cannot write " + tmp);
        }
    }
    commit(tmp, path);
}

}  // namespace caustics
