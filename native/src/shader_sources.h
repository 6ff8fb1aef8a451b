// GLSL sources embedded at build time from shaders/ (cmake/embed_shaders.cmake).
#pragma once

#include <string>
#include <vector>

namespace deferred {

struct ShaderSource {
    const char* name;  // file name inside shaders/, e.g. "bsdf_lib.glsl"
    const char* text;
};

const std::vector<ShaderSource>& embedded_shader_sources();

}  // namespace deferred
