#include "shader_library.h"

#include "shader_sources.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <regex>
#include <sstream>

namespace deferred {

std::string ShaderVariant::key() const {
    std::string k;
    for (const auto& d : defines) k += d + ";";
    return k;
}

ShaderLibrary::ShaderLibrary() {
    for (const ShaderSource& s : embedded_shader_sources()) {
        sources_[s.name] = s.text;
        file_ids_.push_back(s.name);
    }
}

void ShaderLibrary::expand_into(const std::string& file, std::string& out,
                                std::vector<std::string>& included) const {
    if (std::find(included.begin(), included.end(), file) != included.end()) return;
    included.push_back(file);
    const std::string* text = nullptr;
    int file_id = static_cast<int>(file_ids_.size());  // generated files: "source N" in logs
    if (auto it = sources_.find(file); it != sources_.end()) {
        text = &it->second;
        file_id = static_cast<int>(std::find(file_ids_.begin(), file_ids_.end(), file) - file_ids_.begin());
    } else if (generated_) {
        if (auto g = generated_->find(file); g != generated_->end()) text = &g->second;
    }
    if (!text && file == kMaterialGraphFile) {
        // Included under #ifdef MATERIAL_GRAPH, which this (preprocessor-
        // unaware) expansion does not see: nothing to add without a graph.
        out += "/* no material graph */\n";
        return;
    }
    if (!text) throw Error("shader file '" + file + "' is not embedded in the library");

    std::istringstream in(*text);
    std::string line;
    int line_no = 0;
    out += "#line 1 " + std::to_string(file_id) + "\n";
    static const std::regex include_re(R"(^\s*#\s*include\s+\"([^\"]+)\"\s*$)");
    std::smatch m;
    while (std::getline(in, line)) {
        ++line_no;
        if (std::regex_match(line, m, include_re)) {
            expand_into(m[1].str(), out, included);
            out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(file_id) + "\n";
        } else {
            out += line;
            out += '\n';
        }
    }
}

std::string ShaderLibrary::expand(const std::string& file, const ShaderVariant& variant) const {
    std::string out = "#version 450 core\n";
    for (const auto& d : variant.defines) out += "#define " + d + "\n";
    std::vector<std::string> included;
    expand_into(file, out, included);
    return out;
}

// Mesa prints "3:42(7): error: ...", NVIDIA "3(42) : error ...": turn the
// source-string number into the file name.
std::string ShaderLibrary::map_log(const std::string& log) const {
    static const std::regex loc_re(R"((^|\n)(\d+)(?::(\d+)\(\d+\)|\((\d+)\)))");
    std::string out;
    auto begin = log.cbegin();
    std::smatch m;
    while (std::regex_search(begin, log.cend(), m, loc_re)) {
        out.append(begin, m[0].first);
        const std::size_t id = std::stoul(m[2].str());
        const std::string line = m[3].matched ? m[3].str() : m[4].str();
        const std::string name = id < file_ids_.size() ? file_ids_[id] : ("source " + m[2].str());
        out += m[1].str() + name + ":" + line;
        begin = m[0].second;
    }
    out.append(begin, log.cend());
    return out;
}

GLuint ShaderLibrary::compile_stage(GLenum stage, const std::string& file,
                                    const ShaderVariant& variant) const {
    const std::string src = expand(file, variant);
    GLuint shader = glCreateShader(stage);
    const char* ptr = src.c_str();
    glShaderSource(shader, 1, &ptr, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
        glGetShaderInfoLog(shader, len, nullptr, log.data());
        glDeleteShader(shader);
        throw Error("compiling shader " + file + " [" + variant.key() + "] failed:\n" + map_log(log.c_str()));
    }
    return shader;
}

GLuint ShaderLibrary::link(const std::vector<GLuint>& stages, const std::string& label) const {
    GLuint program = glCreateProgram();
    for (GLuint s : stages) glAttachShader(program, s);
    glLinkProgram(program);
    for (GLuint s : stages) {
        glDetachShader(program, s);
        glDeleteShader(s);
    }
    GLint ok = GL_FALSE;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint len = 0;
        glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
        glGetProgramInfoLog(program, len, nullptr, log.data());
        glDeleteProgram(program);
        throw Error("linking program " + label + " failed:\n" + map_log(log.c_str()));
    }
    return program;
}

GLuint ShaderLibrary::compute_program(const std::string& comp_file, const ShaderVariant& variant) {
    const std::string key = comp_file + "|" + variant.key();
    auto it = programs_.find(key);
    if (it != programs_.end()) return it->second.get();
    StageTimer timer;
    GLuint p = link({compile_stage(GL_COMPUTE_SHADER, comp_file, variant)}, key);
    programs_.emplace(key, Program(p));
    ++compile_count_;
    compile_ms_ += timer.lap_ms();
    return p;
}

GLuint ShaderLibrary::graphics_program(const std::string& vert_file, const std::string& frag_file,
                                       const ShaderVariant& variant,
                                       const std::map<std::string, std::string>& generated) {
    std::string key = vert_file + "+" + frag_file + "|" + variant.key();
    for (const auto& [name, text] : generated) key += "|" + name + ":" + text;
    auto it = programs_.find(key);
    if (it != programs_.end()) return it->second.get();
    struct Scope {
        const std::map<std::string, std::string>*& slot;
        ~Scope() { slot = nullptr; }
    } scope{generated_};
    generated_ = &generated;
    StageTimer timer;
    GLuint vs = compile_stage(GL_VERTEX_SHADER, vert_file, variant);
    GLuint fs = 0;
    try {
        fs = compile_stage(GL_FRAGMENT_SHADER, frag_file, variant);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    GLuint p = link({vs, fs}, vert_file + "+" + frag_file + "|" + variant.key());
    programs_.emplace(key, Program(p));
    ++compile_count_;
    compile_ms_ += timer.lap_ms();
    return p;
}

}  // namespace deferred
