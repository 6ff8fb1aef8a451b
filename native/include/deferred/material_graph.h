// Node materials: the typed dataflow graph (IR) the add-on builds from a
// Blender node tree, and the images its texture nodes read.
//
// The graph is generic: each node names a GLSL function of the node library
// (shaders/nodes/) and lists its arguments; node semantics live in the
// add-on's node specs and in that GLSL, not here (see
// addon/deferred_render/materials/CONTRACT.md). The renderer turns a graph
// into a geometry-pass fragment shader (native/src/material_codegen.cpp).
// Two materials whose graphs differ only in `constants` share one program:
// the constants live in a buffer, so editing a value never recompiles.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

enum class SocketType : std::uint8_t { Float = 0, Color = 1, Vector = 2, Closure = 3 };

struct GraphArg {
    enum class Kind : std::uint8_t {
        Int,      // literal `value` compiled into the shader (enums): structural
        Const,    // `type` read from the constants at `value` (float: 1, colour/vector: 3 floats)
        Block,    // the int offset `value` of a block of `output` floats in the constants (read with mat_const)
        Link,     // output `output` of the earlier node `node`, of type `from`, converted to `type`
        Shading,  // a value of the shading point named `name` (N, P, uv, attr0, ...)
        Image,    // the sampler2D of the graph's image slot `value`
    };
    Kind kind = Kind::Int;
    SocketType type = SocketType::Float;
    std::int32_t value = 0;
    std::int32_t node = -1;
    std::int32_t output = 0;
    SocketType from = SocketType::Float;
    std::string name;

    // Named constructors, one per kind (the add-on's bindings build the same
    // from its tuples; C++ callers: tests, benchmarks).
    static GraphArg literal(std::int32_t v) {
        GraphArg a;
        a.value = v;
        return a;
    }
    static GraphArg constant(SocketType t, std::int32_t offset) {
        GraphArg a;
        a.kind = Kind::Const;
        a.type = t;
        a.value = offset;
        return a;
    }
    static GraphArg block(std::int32_t offset, std::int32_t count) {
        GraphArg a;
        a.kind = Kind::Block;
        a.value = offset;
        a.output = count;
        return a;
    }
    static GraphArg link(SocketType t, std::int32_t node, std::int32_t output, SocketType from) {
        GraphArg a;
        a.kind = Kind::Link;
        a.type = t;
        a.node = node;
        a.output = output;
        a.from = from;
        return a;
    }
    static GraphArg shading(std::string shading_name) {
        GraphArg a;
        a.kind = Kind::Shading;
        a.name = std::move(shading_name);
        return a;
    }
    static GraphArg image(std::int32_t slot) {
        GraphArg a;
        a.kind = Kind::Image;
        a.value = slot;
        return a;
    }
};

struct GraphNode {
    std::string func;                  // GLSL identifier in shaders/nodes/
    std::vector<GraphArg> args;        // in call order; outputs follow as `out` parameters
    std::vector<SocketType> outputs;
};

struct MaterialGraph {
    std::string name;                  // the material's, for messages
    std::vector<GraphNode> nodes;      // topological order: links point to earlier nodes
    std::int32_t surface_node = -1;    // the closure reaching the Material Output's Surface
    std::int32_t surface_output = 0;
    std::vector<float> constants;      // per material: values, not structure
    std::vector<std::uint32_t> images;       // image slot -> image id (Renderer::add_image)
    std::vector<std::string> attributes;     // attribute slot k (Shading "attrK") -> mesh attribute name
                                             // (one starting with kFlatAttributePrefix is read flat)
    // The closure's alpha can be below 1 (Principled Alpha, a Transparent
    // BSDF): the program discards by it (stochastic transparency), draws
    // its own depth pre-pass and its own shadow-map casters.
    bool alpha = false;
    // Some closure's normal is not the smooth normal (Bump, Normal Map, any
    // vector): the lighting then also needs the smooth one (G-buffer).
    bool closure_normal = false;
    // Shader AOVs: slot k (node_aov_output's first argument) writes the
    // view layer's AOV of this name.
    std::vector<std::string> aovs;
};
constexpr int kMaxGraphAovs = 8;  // MAX_GRAPH_AOVS in material_lib.glsl
// A mesh attribute constant per triangle whose exact value matters (the
// add-on's "island:", Random Per Island, which users hash): the geometry
// pass reads it with a flat varying rather than interpolating three equal
// values, which may move the last bit. One per graph.
constexpr const char* kFlatAttributePrefix = "island:";

// An image for texture nodes: RGBA, row 0 at the bottom (Blender's order).
// 8-bit data is kept 8-bit on the GPU (RGBA8, read as value/255), float data
// as RGBA32F; the node library does every conversion Cycles does.
struct ImageData {
    int width = 0, height = 0;
    const std::uint8_t* bytes = nullptr;  // width*height*4, or
    const float* floats = nullptr;        // width*height*4
};

// Per-corner data of a mesh that node materials read by name ("uv:UVMap",
// "tangent:UVMap", "color:Col", ...): `components` floats per triangle
// corner, in the order of MeshData::indices.
struct CornerAttribute {
    std::string name;
    int components = 0;  // 1..4
    const float* data = nullptr;  // object space for directions (tangents): the node library transforms them
};

}  // namespace deferred
