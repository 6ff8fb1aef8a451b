/* The node library: every GLSL function a material graph may call. One file
 * per family; each function cites the Cycles 3.4 source it reproduces. */
#include "nodes/hash_lib.glsl"
#include "nodes/node_shader_lib.glsl"
#include "nodes/node_input_lib.glsl"
#include "nodes/node_vector_lib.glsl"
#include "nodes/node_converter_lib.glsl"
#include "nodes/node_color_lib.glsl"
#include "nodes/node_texture_lib.glsl"
#include "nodes/node_image_lib.glsl"
