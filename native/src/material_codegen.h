// Node material graph (IR) -> GLSL: the body of the geometry pass's
// material evaluation (shaders/material_lib.glsl calls material_graph_eval).
#pragma once

#include <deferred/material_graph.h>

#include <string>
#include <vector>

namespace deferred {

// Throws InvalidInput naming the node and argument when the graph is not
// well formed: an identifier outside the node library's naming, a link to a
// later node or a missing output, a conversion Blender does not make
// (closure <-> value), a constant or block outside `constants`, an image
// slot without an image, an unknown shading value. No GL.
void validate_material_graph(const MaterialGraph& graph);

// GLSL of `void material_graph_eval(out Closure surface)` for a valid graph
// (without the includes of the node library files it calls: see
// MaterialModule::program).
// Depends on the graph's structure only (never on constant values), so it
// doubles as the program's cache key.
std::string material_graph_glsl(const MaterialGraph& graph);

// The GLSL functions a graph calls.
std::vector<std::string> material_graph_functions(const MaterialGraph& graph);

// GLSL type of a socket type.
const char* glsl_type(SocketType t);

// Largest number of attribute slots (Shading "attr0".."attrN-1") and image
// slots one material may use.
constexpr int kMaxGraphAttributes = 8;
constexpr int kMaxGraphImages = 16;

}  // namespace deferred
