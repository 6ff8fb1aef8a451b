#include "material_codegen.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

namespace deferred {

namespace {

[[noreturn]] void invalid(const std::string& what) { throw InvalidInput("material graph: " + what); }

// Values of the shading point the node library may read (material_lib.glsl).
// name -> GLSL expression.
const std::map<std::string, std::string>& shading_values() {
    static const std::map<std::string, std::string> values = [] {
        std::map<std::string, std::string> v = {
            {"N", "g_sd.N"},
            {"Ng", "g_sd.Ng"},
            {"P", "g_sd.P"},
            {"I", "g_sd.I"},
            {"generated", "g_sd.generated"},
            {"uv", "g_sd.uv"},
            {"N_object", "g_sd.N_object"},
            {"P_object", "g_sd.P_object"},
            {"object_location", "g_sd.object_location"},
            {"object_color", "g_sd.object_color.rgb"},
            {"object_alpha", "g_sd.object_color.a"},
            {"object_index", "g_sd.object_index"},
            {"material_index", "g_sd.material_index"},
            {"object_random", "g_sd.object_random"},
            {"backfacing", "g_sd.backfacing"},
            {"view_distance", "g_sd.view_distance"},
            {"view_depth", "g_sd.view_depth"},
            {"attr_none", "vec4(0.0)"},
        };
        for (int k = 0; k < kMaxGraphAttributes; ++k)
            v["attr" + std::to_string(k)] = "g_sd.attr[" + std::to_string(k) + "]";
        return v;
    }();
    return values;
}

bool is_identifier(const std::string& s) {
    if (s.empty() || s.size() > 64 || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
    for (char c : s)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
    return true;
}

int float_count(SocketType t) { return t == SocketType::Float ? 1 : 3; }

std::string output_name(int node, int output) {
    return "n" + std::to_string(node) + "_" + std::to_string(output);
}

// Blender's implicit socket conversions (Cycles ConvertNode).
std::string convert(const std::string& value, SocketType from, SocketType to) {
    if (from == to) return value;
    if (to == SocketType::Float)
        return (from == SocketType::Color ? "node_color_to_float(" : "node_vector_to_float(") + value + ")";
    if (from == SocketType::Float) return "vec3(" + value + ")";
    return value;  // colour <-> vector: the same three numbers
}

}  // namespace

std::vector<std::string> material_graph_functions(const MaterialGraph& g) {
    std::vector<std::string> out;
    for (const GraphNode& n : g.nodes)
        if (std::find(out.begin(), out.end(), n.func) == out.end()) out.push_back(n.func);
    return out;
}

const char* glsl_type(SocketType t) {
    switch (t) {
        case SocketType::Float: return "float";
        case SocketType::Color:
        case SocketType::Vector: return "vec3";
        case SocketType::Closure: return "Closure";
    }
    return "float";
}

void validate_material_graph(const MaterialGraph& g) {
    const std::size_t n = g.nodes.size();
    if (n > 4096) invalid(std::to_string(n) + " nodes exceed the limit of 4096");
    if (g.constants.size() > (1u << 20)) invalid("more than 2^20 constants");
    if (g.images.size() > std::size_t(kMaxGraphImages))
        invalid(std::to_string(g.images.size()) + " images exceed the limit of " + std::to_string(kMaxGraphImages));
    if (g.attributes.size() > std::size_t(kMaxGraphAttributes))
        invalid(std::to_string(g.attributes.size()) + " attributes exceed the limit of " +
                std::to_string(kMaxGraphAttributes));
    for (float c : g.constants)
        if (!std::isfinite(c)) invalid("a constant is NaN or infinite");
    for (std::size_t i = 0; i < n; ++i) {
        const GraphNode& node = g.nodes[i];
        const std::string where = "node " + std::to_string(i) + " (" + node.func + ")";
        if (!is_identifier(node.func) || node.func.rfind("node_", 0) != 0)
            invalid(where + ": function name must be an identifier starting with node_");
        if (node.args.size() + node.outputs.size() > 64) invalid(where + ": too many arguments");
        for (std::size_t a = 0; a < node.args.size(); ++a) {
            const GraphArg& arg = node.args[a];
            const std::string at = where + " argument " + std::to_string(a);
            switch (arg.kind) {
                case GraphArg::Kind::Int: break;
                case GraphArg::Kind::Const:
                    if (arg.type == SocketType::Closure) invalid(at + ": a closure cannot be a constant");
                    if (arg.value < 0 || std::size_t(arg.value) + std::size_t(float_count(arg.type)) > g.constants.size())
                        invalid(at + ": constant offset " + std::to_string(arg.value) + " is outside the constants");
                    break;
                case GraphArg::Kind::Block:
                    // Every float the node library may read (mat_const(offset + i),
                    // i < length) lies inside the material's constants.
                    if (arg.value < 0 || arg.output < 0 ||
                        std::size_t(arg.value) + std::size_t(arg.output) > g.constants.size())
                        invalid(at + ": block of " + std::to_string(arg.output) + " floats at " +
                                std::to_string(arg.value) + " is outside the constants");
                    break;
                case GraphArg::Kind::Link: {
                    if (arg.node < 0 || std::size_t(arg.node) >= i)
                        invalid(at + ": links to node " + std::to_string(arg.node) +
                                ", which is not an earlier node (graphs are acyclic, in topological order)");
                    const GraphNode& src = g.nodes[std::size_t(arg.node)];
                    if (arg.output < 0 || std::size_t(arg.output) >= src.outputs.size())
                        invalid(at + ": node " + std::to_string(arg.node) + " has no output " + std::to_string(arg.output));
                    if (src.outputs[std::size_t(arg.output)] != arg.from)
                        invalid(at + ": the link's source type does not match node " + std::to_string(arg.node) + "'s output");
                    if ((arg.from == SocketType::Closure) != (arg.type == SocketType::Closure))
                        invalid(at + ": closures connect only to closures");
                    break;
                }
                case GraphArg::Kind::Shading:
                    if (!shading_values().count(arg.name)) invalid(at + ": unknown shading value '" + arg.name + "'");
                    if (arg.name.rfind("attr", 0) == 0 && arg.name != "attr_none" && std::size_t(std::stoi(arg.name.substr(4))) >= g.attributes.size())
                        invalid(at + ": " + arg.name + " has no attribute name");
                    break;
                case GraphArg::Kind::Image:
                    if (arg.value < 0 || std::size_t(arg.value) >= g.images.size())
                        invalid(at + ": image slot " + std::to_string(arg.value) + " has no image");
                    break;
            }
        }
    }
    if (g.aovs.size() > std::size_t(kMaxGraphAovs))
        invalid(std::to_string(g.aovs.size()) + " AOV outputs exceed the limit of " + std::to_string(kMaxGraphAovs));
    for (const GraphNode& node : g.nodes)
        if (node.func == "node_aov_output" &&
            (node.args.empty() || node.args[0].kind != GraphArg::Kind::Int || node.args[0].value < 0 ||
             std::size_t(node.args[0].value) >= g.aovs.size()))
            invalid("an AOV output names no AOV slot of the graph");
    if (g.surface_node >= 0) {
        if (std::size_t(g.surface_node) >= n) invalid("surface node " + std::to_string(g.surface_node) + " does not exist");
        const GraphNode& s = g.nodes[std::size_t(g.surface_node)];
        if (g.surface_output < 0 || std::size_t(g.surface_output) >= s.outputs.size() ||
            s.outputs[std::size_t(g.surface_output)] != SocketType::Closure)
            invalid("the surface output is not a closure output");
    }
}

std::string material_graph_glsl(const MaterialGraph& g) {
    std::ostringstream out;
    out << "/* Generated from a node material graph (material_codegen.cpp). */\n";
    out << "void material_graph_eval(out Closure surface) {\n";
    if (!g.aovs.empty()) out << "    for (int k = 0; k < MAX_GRAPH_AOVS; ++k) g_aov[k] = vec4(0.0);\n";
    for (std::size_t i = 0; i < g.nodes.size(); ++i) {
        const GraphNode& node = g.nodes[i];
        for (std::size_t o = 0; o < node.outputs.size(); ++o)
            out << "    " << glsl_type(node.outputs[o]) << " " << output_name(int(i), int(o)) << ";\n";
        out << "    " << node.func << "(";
        bool first = true;
        auto sep = [&]() {
            if (!first) out << ", ";
            first = false;
        };
        for (const GraphArg& arg : node.args) {
            sep();
            switch (arg.kind) {
                case GraphArg::Kind::Int: out << arg.value; break;
                case GraphArg::Kind::Const:
                    out << (arg.type == SocketType::Float ? "mat_const(" : "mat_const3(") << arg.value << ")";
                    break;
                case GraphArg::Kind::Block: out << arg.value; break;
                case GraphArg::Kind::Link:
                    out << convert(output_name(arg.node, arg.output), arg.from, arg.type);
                    break;
                case GraphArg::Kind::Shading: out << shading_values().at(arg.name); break;
                case GraphArg::Kind::Image: out << "material_images[" << arg.value << "]"; break;
            }
        }
        for (std::size_t o = 0; o < node.outputs.size(); ++o) {
            sep();
            out << output_name(int(i), int(o));
        }
        out << ");\n";
    }
    if (g.surface_node >= 0)
        out << "    surface = " << output_name(g.surface_node, g.surface_output) << ";\n";
    else
        out << "    surface = closure_none();\n";
    out << "}\n";
    return out.str();
}

}  // namespace deferred
