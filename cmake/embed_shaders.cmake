# Turns every file of SHADER_DIR into a C++ string table (name -> source) so the
# native library carries its GLSL and needs no files at run time (the add-on
# folder holds only the .so). Run as a script: cmake -DSHADER_DIR=.. -DOUTPUT=.. -P
file(GLOB_RECURSE shader_files RELATIVE "${SHADER_DIR}" "${SHADER_DIR}/*.glsl" "${SHADER_DIR}/*.h")
list(SORT shader_files)
set(body "// Generated from shaders/ by cmake/embed_shaders.cmake; do not edit.\n#include \"shader_sources.h\"\nnamespace deferred {\nconst std::vector<ShaderSource>& embedded_shader_sources() {\n  static const std::vector<ShaderSource> sources = {\n")
foreach(f IN LISTS shader_files)
  file(READ "${SHADER_DIR}/${f}" content)
  # Raw string literal with a delimiter GLSL never contains.
  string(APPEND body "    {\"${f}\", R\"glsl_src(${content})glsl_src\"},\n")
endforeach()
string(APPEND body "  };\n  return sources;\n}\n}  // namespace deferred\n")
file(WRITE "${OUTPUT}.tmp" "${body}")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
