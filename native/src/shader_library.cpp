#include "shader_library.h"

#include "shader_sources.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <regex>
#include <thread>

#include <unistd.h>
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
    static const std::regex branch_re(R"(^\s*#\s*(endif|else|elif)\b.*)");
    std::smatch m;
    while (std::getline(in, line)) {
        ++line_no;
        if (std::regex_match(line, m, include_re)) {
            expand_into(m[1].str(), out, included);
            out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(file_id) + "\n";
        } else {
            out += line;
            out += '\n';
            // An include inside a group the preprocessor skips takes its
            // #line directives with it, the one back to this file included:
            // number again after each branch, or the log names the wrong
            // file and line (light_lib.glsl's lines after a skipped
            // shadow_lib.glsl were reported ~390 lines on, in another file).
            if (std::regex_match(line, branch_re))
                out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(file_id) + "\n";
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

std::string ShaderLibrary::shader_error(GLenum stage, GLuint shader, const std::string& label) const {
    GLint len = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetShaderInfoLog(shader, len, nullptr, log.data());
    const char* kind = stage == GL_VERTEX_SHADER ? "vertex" : stage == GL_FRAGMENT_SHADER ? "fragment" : "compute";
    return std::string("compiling the ") + kind + " shader of " + label + " failed:\n" + map_log(log.c_str());
}

namespace {

// FNV-1a, 64 bit: the disk cache's file name; a second 64-bit hash of the
// same key (another seed) is stored in the file and compared on load.
std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : s) {
        h ^= c;
        h *= 1099511628211ull;
    }
    return h;
}

// Where program binaries are kept: DEFERRED_SHADER_CACHE (a folder, or "off"),
// else $XDG_CACHE_HOME/deferred_render/programs, else ~/.cache/...
std::string cache_folder() {
    if (const char* env = std::getenv("DEFERRED_SHADER_CACHE")) {
        const std::string v = env;
        if (v == "off" || v == "0" || v.empty()) return "";
        return v;
    }
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/deferred_render/programs";
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/deferred_render/programs";
    return "";
}

}  // namespace

ShaderLibrary::~ShaderLibrary() {
    for (auto& [key, p] : pending_) {
        for (auto& [stage, shader] : p.shaders) glDeleteShader(shader);
        if (p.program) glDeleteProgram(p.program);
    }
}

void ShaderLibrary::init_driver() {
    if (!driver_.empty()) return;
    for (GLenum e : {GL_VENDOR, GL_RENDERER, GL_VERSION}) {
        const GLubyte* v = glGetString(e);
        driver_ += v ? reinterpret_cast<const char*>(v) : "";
        driver_ += '\n';
    }
    GLint formats = 0;
    glGetIntegerv(GL_NUM_PROGRAM_BINARY_FORMATS, &formats);
    cache_dir_ = formats > 0 ? cache_folder() : "";
    // The driver's own compiler threads, one per hardware thread; without one
    // of the extensions a compile finishes inside the call that issues it.
    const char* env = std::getenv("DEFERRED_PARALLEL_COMPILE");
    if (env && std::string(env) == "0") return;
    const GLuint threads = std::max(1u, std::thread::hardware_concurrency());
    if (epoxy_has_gl_extension("GL_KHR_parallel_shader_compile")) {
        glMaxShaderCompilerThreadsKHR(threads);
        parallel_ = true;
    } else if (epoxy_has_gl_extension("GL_ARB_parallel_shader_compile")) {
        glMaxShaderCompilerThreadsARB(threads);
        parallel_ = true;
    }
}

bool ShaderLibrary::parallel_compile() {
    init_driver();
    return parallel_;
}

// A program from its stage sources: from the in-memory map, else the disk
// cache (glProgramBinary, keyed by the sources and the driver's strings: a
// driver update misses and recompiles), else compiled, linked and stored.
void ShaderLibrary::issue(const std::string& key, const std::vector<std::pair<GLenum, std::string>>& stages,
                          const std::string& label) {
    init_driver();
    const auto t0 = std::chrono::steady_clock::now();
    std::string all = driver_;
    for (const auto& [stage, src] : stages) all += std::to_string(stage) + ":" + src;
    const std::uint64_t h1 = fnv1a(all), h2 = fnv1a(all, 0x9e3779b97f4a7c15ull);
    char name[40];
    std::snprintf(name, sizeof name, "%016llx.bin", static_cast<unsigned long long>(h1));
    const std::string path = cache_dir_.empty() ? "" : cache_dir_ + "/" + name;

    if (!path.empty()) {
        if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
            std::uint64_t stored = 0;
            GLenum format = 0;
            std::vector<char> binary;
            if (std::fread(&stored, sizeof stored, 1, f) == 1 && stored == h2 &&
                std::fread(&format, sizeof format, 1, f) == 1) {
                char buf[65536];
                std::size_t n;
                while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) binary.insert(binary.end(), buf, buf + n);
            }
            std::fclose(f);
            if (!binary.empty()) {
                GLuint p = glCreateProgram();
                glProgramBinary(p, format, binary.data(), GLsizei(binary.size()));
                GLint ok = GL_FALSE;
                glGetProgramiv(p, GL_LINK_STATUS, &ok);
                while (glGetError() != GL_NO_ERROR) {
                }
                if (ok) {
                    programs_.emplace(key, Program(p));
                    ++disk_loads_;
                    load_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
                    return;
                }
                glDeleteProgram(p);  // stale or refused: compile below
            }
        }
    }

    // Compile and link without asking for their status: with the driver's
    // own threads these calls return at once and the work goes on there;
    // complete() asks, and waits.
    Pending p;
    p.label = label;
    p.path = path;
    p.check = h2;
    for (const auto& [stage, src] : stages) {
        const GLuint shader = glCreateShader(stage);
        const char* ptr = src.c_str();
        glShaderSource(shader, 1, &ptr, nullptr);
        glCompileShader(shader);
        p.shaders.emplace_back(stage, shader);
    }
    p.program = glCreateProgram();
    if (!path.empty()) glProgramParameteri(p.program, GL_PROGRAM_BINARY_RETRIEVABLE_HINT, GL_TRUE);
    for (const auto& [stage, shader] : p.shaders) glAttachShader(p.program, shader);
    glLinkProgram(p.program);
    pending_[key] = std::move(p);
    compile_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

GLuint ShaderLibrary::complete(const std::string& key) {
    auto node = pending_.extract(key);
    Pending& p = node.mapped();
    const auto t0 = std::chrono::steady_clock::now();
    auto discard = [&] {
        for (auto& [stage, shader] : p.shaders) glDeleteShader(shader);
        glDeleteProgram(p.program);
    };
    for (const auto& [stage, shader] : p.shaders) {
        GLint ok = GL_FALSE;
        glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);  // waits for the compile
        if (!ok) {
            std::string message;
            try {
                message = shader_error(stage, shader, p.label);
            } catch (...) {
                discard();  // the entry has left pending_: nothing else deletes its objects
                throw;
            }
            discard();
            throw Error(message);
        }
    }
    GLint ok = GL_FALSE;
    glGetProgramiv(p.program, GL_LINK_STATUS, &ok);  // waits for the link
    if (!ok) {
        std::string message;
        try {
            GLint len = 0;
            glGetProgramiv(p.program, GL_INFO_LOG_LENGTH, &len);
            std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
            glGetProgramInfoLog(p.program, len, nullptr, log.data());
            message = "linking program " + p.label + " failed:\n" + map_log(log.c_str());
        } catch (...) {
            discard();
            throw;
        }
        discard();
        throw Error(message);
    }
    for (const auto& [stage, shader] : p.shaders) {
        glDetachShader(p.program, shader);
        glDeleteShader(shader);
    }
    const GLuint program = p.program;
    programs_.emplace(key, Program(program));
    ++compile_count_;
    compile_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

    const std::string& path = p.path;
    if (!path.empty()) {
        GLint length = 0;
        glGetProgramiv(program, GL_PROGRAM_BINARY_LENGTH, &length);
        if (length > 0) {
            std::vector<char> binary(std::size_t(length), 0);
            GLenum format = 0;
            glGetProgramBinary(program, length, nullptr, &format, binary.data());
            std::error_code ec;
            std::filesystem::create_directories(cache_dir_, ec);
            // Unique per process and library: parallel renders share the folder.
            const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + "_" +
                                    std::to_string(reinterpret_cast<std::uintptr_t>(this));
            if (std::FILE* f = std::fopen(tmp.c_str(), "wb")) {
                const bool written = std::fwrite(&p.check, sizeof p.check, 1, f) == 1 &&
                                     std::fwrite(&format, sizeof format, 1, f) == 1 &&
                                     std::fwrite(binary.data(), 1, binary.size(), f) == binary.size();
                std::fclose(f);
                // Renamed into place only when whole: a reader never sees half a file.
                if (written) std::filesystem::rename(tmp, path, ec);
                if (!written || ec) std::filesystem::remove(tmp, ec);
                if (compile_count_ == 1) prune_disk_cache();
            }
        }
        while (glGetError() != GL_NO_ERROR) {
        }
    }
    return program;
}

GLuint ShaderLibrary::build(const std::string& key, const std::vector<std::pair<GLenum, std::string>>& stages,
                            const std::string& label) {
    if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();
    if (pending_.find(key) == pending_.end()) {
        issue(key, stages, label);
        if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();  // from the disk cache
    }
    return complete(key);
}

namespace {

// nodes/ file -> functions it defines, and the node files it calls into.
// The sources are embedded, so the index is built once per process.
struct NodeFileIndex {
    std::map<std::string, std::vector<std::string>> definitions, dependencies;
};

const NodeFileIndex& node_file_index() {
    static const NodeFileIndex index = [] {
        static const std::regex def_re(R"((?:^|\n)[ \t]*(?:void|float|int|uint|bool|vec[234]|ivec[234]|uvec[234]|mat[234]|double|dvec[234]|Closure)[ \t]+([A-Za-z_]\w*)[ \t]*\([^;{}]*\)\s*\{)");  // definitions, not prototypes
        static const std::regex ident_re(R"([A-Za-z_]\w*)");
        NodeFileIndex idx;
        std::map<std::string, std::string> defined_in, text_of;
        for (const ShaderSource& src : embedded_shader_sources()) {
            const std::string file = src.name;
            if (file.rfind("nodes/", 0) != 0) continue;
            const std::string text = src.text;
            text_of[file] = text;
            auto& defs = idx.definitions[file];
            for (std::sregex_iterator it(text.begin(), text.end(), def_re), end; it != end; ++it) {
                defs.push_back((*it)[1].str());
                defined_in.emplace((*it)[1].str(), file);
            }
        }
        for (const auto& [file, defs] : idx.definitions) {
            const std::string& text = text_of.at(file);
            auto& deps = idx.dependencies[file];
            for (std::sregex_iterator it(text.begin(), text.end(), ident_re), end; it != end; ++it) {
                auto d = defined_in.find(it->str());
                if (d != defined_in.end() && d->second != file &&
                    std::find(deps.begin(), deps.end(), d->second) == deps.end())
                    deps.push_back(d->second);
            }
        }
        return idx;
    }();
    return index;
}

}  // namespace

std::vector<std::string> ShaderLibrary::node_files_for(const std::vector<std::string>& functions) {
    const NodeFileIndex& index = node_file_index();
    std::vector<std::string> order, visiting;
    std::function<void(const std::string&)> visit = [&](const std::string& file) {
        if (std::find(order.begin(), order.end(), file) != order.end()) return;
        if (std::find(visiting.begin(), visiting.end(), file) != visiting.end()) return;  // mutual: order as found
        visiting.push_back(file);
        if (auto deps = index.dependencies.find(file); deps != index.dependencies.end())
            for (const std::string& dep : deps->second) visit(dep);
        order.push_back(file);
    };
    for (const std::string& f : functions) {
        std::string file;
        for (const auto& [name, defs] : index.definitions)
            if (std::find(defs.begin(), defs.end(), f) != defs.end()) file = name;
        if (file.empty()) throw Error("no file of the node library defines " + f + "()");
        visit(file);
    }
    return order;
}

// The disk cache keeps at most kMaxCachedPrograms files: the least recently
// written go first (checked once per library, i.e. per renderer).
void ShaderLibrary::prune_disk_cache() const {
    constexpr std::size_t kMaxCachedPrograms = 4096;
    std::error_code ec;
    std::vector<std::pair<std::filesystem::file_time_type, std::filesystem::path>> files;
    for (const auto& entry : std::filesystem::directory_iterator(cache_dir_, ec))
        if (entry.path().extension() == ".bin") files.emplace_back(entry.last_write_time(ec), entry.path());
    if (files.size() <= kMaxCachedPrograms) return;
    std::sort(files.begin(), files.end());
    for (std::size_t i = 0; i + kMaxCachedPrograms < files.size(); ++i) std::filesystem::remove(files[i].second, ec);
}

std::string ShaderLibrary::compute_key(const std::string& comp_file, const ShaderVariant& variant,
                                       const std::map<std::string, std::string>& generated) const {
    std::string key = comp_file + "|" + variant.key();
    for (const auto& [name, text] : generated) key += "|" + name + ":" + text;
    return key;
}

std::string ShaderLibrary::graphics_key(const std::string& vert_file, const std::string& frag_file,
                                        const ShaderVariant& variant,
                                        const std::map<std::string, std::string>& generated) const {
    std::string key = vert_file + "+" + frag_file + "|" + variant.key();
    for (const auto& [name, text] : generated) key += "|" + name + ":" + text;
    return key;
}

namespace {
// generated_ points at a call's generated files while its sources expand.
struct GeneratedScope {
    const std::map<std::string, std::string>*& slot;
    GeneratedScope(const std::map<std::string, std::string>*& s, const std::map<std::string, std::string>& g)
        : slot(s) {
        slot = &g;
    }
    ~GeneratedScope() { slot = nullptr; }
};
}  // namespace

GLuint ShaderLibrary::compute_program(const std::string& comp_file, const ShaderVariant& variant,
                                      const std::map<std::string, std::string>& generated) {
    const std::string key = compute_key(comp_file, variant, generated);
    if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();
    if (pending_.count(key)) return complete(key);
    GeneratedScope scope(generated_, generated);
    return build(key, {{GL_COMPUTE_SHADER, expand(comp_file, variant)}}, comp_file + "|" + variant.key());
}

GLuint ShaderLibrary::graphics_program(const std::string& vert_file, const std::string& frag_file,
                                       const ShaderVariant& variant,
                                       const std::map<std::string, std::string>& generated) {
    const std::string key = graphics_key(vert_file, frag_file, variant, generated);
    if (auto it = programs_.find(key); it != programs_.end()) return it->second.get();
    if (pending_.count(key)) return complete(key);
    GeneratedScope scope(generated_, generated);
    const std::string label = vert_file + "+" + frag_file + "|" + variant.key();
    return build(key, {{GL_VERTEX_SHADER, expand(vert_file, variant)}, {GL_FRAGMENT_SHADER, expand(frag_file, variant)}},
                 label);
}

void ShaderLibrary::prefetch_compute(const std::string& comp_file, const ShaderVariant& variant,
                                     const std::map<std::string, std::string>& generated) {
    if (!parallel_compile()) return;
    const std::string key = compute_key(comp_file, variant, generated);
    if (programs_.count(key) || pending_.count(key)) return;
    try {
        GeneratedScope scope(generated_, generated);
        issue(key, {{GL_COMPUTE_SHADER, expand(comp_file, variant)}}, comp_file + "|" + variant.key());
    } catch (const std::exception&) {
        // The request reports it.
    }
}

void ShaderLibrary::prefetch_graphics(const std::string& vert_file, const std::string& frag_file,
                                      const ShaderVariant& variant, const std::map<std::string, std::string>& generated) {
    if (!parallel_compile()) return;
    const std::string key = graphics_key(vert_file, frag_file, variant, generated);
    if (programs_.count(key) || pending_.count(key)) return;
    try {
        GeneratedScope scope(generated_, generated);
        issue(key, {{GL_VERTEX_SHADER, expand(vert_file, variant)}, {GL_FRAGMENT_SHADER, expand(frag_file, variant)}},
              vert_file + "+" + frag_file + "|" + variant.key());
    } catch (const std::exception&) {
        // The request reports it.
    }
}

}  // namespace deferred
