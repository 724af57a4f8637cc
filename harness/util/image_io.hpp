#pragma once
// Image files through OpenImageIO, written atomically (temporary name, then rename).
#include <string>

#include <caustics/util/image.hpp>

namespace caustics {

void write_exr(const Image& image, const std::string& path);
Image read_image(const std::string& path);   // any format OIIO reads; float pixels
// 8-bit sRGB PNG of a linear image; `exposure` scales before the transfer curve.
void write_png(const Image& linear, const std::string& path, double exposure = 1.0);

// Writes text to path atomically (path.tmp.<pid>, then rename).
void write_text_atomic(const std::string& path, const std::string& text);

// ".tmp.<host>.<pid>": the temporary name's suffix of an atomic write, unique across the processes of
// every node that shares a file system (sharded sweeps on a cluster write one cache and one folder).
std::string temporary_suffix();

}  // namespace caustics
