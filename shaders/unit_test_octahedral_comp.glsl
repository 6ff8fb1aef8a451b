/* GPU unit test (tests/native/test_normal_encoding.cpp): writes a buffer of
 * unit vectors into an RG16 unorm image through octahedral_encode, exactly as
 * the G-buffer stores normals, then the test decodes them on the GPU too. */
#include "octahedral_lib.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Dirs { vec4 dirs[]; };
layout(std430, binding = 1) writeonly buffer Decoded { vec4 decoded[]; };
layout(binding = 0, rg16) uniform image2D encoded; /* the G-buffer's normal format */

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(dirs.length())) return;
    int width = imageSize(encoded).x;
    ivec2 texel = ivec2(int(i) % width, int(i) / width);
    imageStore(encoded, texel, vec4(octahedral_encode(dirs[i].xyz), 0.0, 0.0));
    memoryBarrierImage();
    /* Read back through the unorm16 quantisation (same invocation, same texel). */
    vec2 q = imageLoad(encoded, texel).rg;
    decoded[i] = vec4(octahedral_decode(q), 0.0);
}
