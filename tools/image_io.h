// Writing passes to disk: multilayer EXR (Blender's channel naming,
// "ViewLayer.<Pass>.<chan>") and an 8-bit sRGB PNG preview of Combined.
#pragma once

#include <deferred/renderer.h>

#include <string>

namespace deferred::tools {

void write_multilayer_exr(const std::string& path, const FrameResult& frame);
// Standard view transform: linear -> sRGB OETF, clamped; alpha kept.
void write_png_preview(const std::string& path, const PassImage& combined);

}  // namespace deferred::tools
