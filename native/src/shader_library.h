// Builds GL programs from the embedded GLSL files.
//
// A shader file names its dependencies with `#include "file"` lines (the
// shared C++/GLSL headers included); the library expands them once each,
// prepends `#version 450 core` and the variant's `#define`s, and emits
// `#line <line> <file id>` before every chunk so that a compile error is
// reported as "bsdf_lib.glsl:42: ..." instead of a source-string number.
// Programs are cached per (files, defines): only variants a scene needs are
// ever compiled. Linked programs are also kept on disk through
// glProgramBinary (DEFERRED_SHADER_CACHE, default ~/.cache/deferred_render/
// programs), keyed by their full sources and the driver's strings, so a new
// renderer (every final render makes one) loads instead of compiling.
#pragma once

#include "gl_util.h"

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace deferred {

// The generated file a node material's program includes (material_codegen.cpp).
constexpr const char* kMaterialGraphFile = "material_graph.glsl";

struct ShaderVariant {
    std::vector<std::string> defines;  // "NAME" or "NAME VALUE"
    std::string key() const;
};

class ShaderLibrary {
public:
    ShaderLibrary();

    // Expanded source of one file (for tests and error messages).
    std::string expand(const std::string& file, const ShaderVariant& variant) const;

    // `generated`: extra files (name -> source) the expansion may include,
    // e.g. a node material's "material_graph.glsl"; part of the cache key.
    GLuint compute_program(const std::string& comp_file, const ShaderVariant& variant,
                           const std::map<std::string, std::string>& generated = {});
    GLuint graphics_program(const std::string& vert_file, const std::string& frag_file,
                            const ShaderVariant& variant,
                            const std::map<std::string, std::string>& generated = {});

    std::size_t compiled_program_count() const { return programs_.size(); }

    // Starts compiling a program that compute_program / graphics_program will
    // be asked for with the same arguments, without waiting for it, where the
    // driver compiles on its own threads (GL_KHR_parallel_shader_compile or
    // the ARB one: the library asks for as many threads as it has). Prefetch
    // a batch, then ask for each: the batch compiles in parallel, and each
    // request reports its own errors as before. Does nothing without the
    // extension, or with DEFERRED_PARALLEL_COMPILE=0 in the environment;
    // never throws (the request will).
    void prefetch_compute(const std::string& comp_file, const ShaderVariant& variant,
                          const std::map<std::string, std::string>& generated = {});
    void prefetch_graphics(const std::string& vert_file, const std::string& frag_file, const ShaderVariant& variant,
                           const std::map<std::string, std::string>& generated = {});
    bool parallel_compile();  // the driver compiles prefetched programs on its own threads
    ~ShaderLibrary();
    ShaderLibrary(const ShaderLibrary&) = delete;
    ShaderLibrary& operator=(const ShaderLibrary&) = delete;

    // The node-library files (shaders/nodes/) that define `functions`, each
    // after the files it calls into: a node material's program includes only
    // these (parsing the whole library costs llvmpipe ~1.2 s per program).
    // Throws Error naming a function no file defines.
    std::vector<std::string> node_files_for(const std::vector<std::string>& functions);
    // Programs compiled and linked (in neither cache) and the time it took;
    // programs loaded from the disk cache (glProgramBinary) and that time.
    std::size_t compile_count() const { return compile_count_; }
    double compile_ms() const { return compile_ms_; }
    std::size_t disk_loads() const { return disk_loads_; }
    double load_ms() const { return load_ms_; }

private:
    // A program whose compile and link were issued, their status not yet asked.
    struct Pending {
        GLuint program = 0;
        std::vector<std::pair<GLenum, GLuint>> shaders;
        std::string label, path;
        std::uint64_t check = 0;  // the disk cache's second hash
    };
    void init_driver();
    // Issues the compile and link (or loads the disk cache's binary) of `key`.
    void issue(const std::string& key, const std::vector<std::pair<GLenum, std::string>>& stages,
               const std::string& label);
    // Waits for a pending program: its errors thrown, its binary stored.
    GLuint complete(const std::string& key);
    std::string shader_error(GLenum stage, GLuint shader, const std::string& label) const;
    GLuint build(const std::string& key, const std::vector<std::pair<GLenum, std::string>>& stages,
                 const std::string& label);
    std::string compute_key(const std::string& comp_file, const ShaderVariant& variant,
                            const std::map<std::string, std::string>& generated) const;
    std::string graphics_key(const std::string& vert_file, const std::string& frag_file, const ShaderVariant& variant,
                             const std::map<std::string, std::string>& generated) const;
    void prune_disk_cache() const;
    void expand_into(const std::string& file, std::string& out, std::vector<std::string>& included) const;
    std::string map_log(const std::string& log) const;

    std::map<std::string, std::string> sources_;
    std::vector<std::string> file_ids_;  // #line source-string number -> file name
    std::map<std::string, Program> programs_;
    const std::map<std::string, std::string>* generated_ = nullptr;  // during one program's expansion
    std::size_t compile_count_ = 0, disk_loads_ = 0;
    double compile_ms_ = 0.0, load_ms_ = 0.0;
    std::map<std::string, Pending> pending_;
    bool parallel_ = false;  // the driver compiles on its own threads (init_driver)
    std::string driver_;     // GL vendor/renderer/version: part of every disk-cache key
    std::string cache_dir_;  // empty: no disk cache (disabled, or the driver has no binary formats)
};

}  // namespace deferred
