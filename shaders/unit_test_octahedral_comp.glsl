/* GPU unit test (tests/native/test_normal_encoding.cpp): writes a buffer of
 * unit vectors into an R32UI image through octahedral_encode and
 * packUnorm2x16, exactly as the G-buffer stores normals, then the test
 * decodes them on the GPU too. */
#include "octahedral_lib.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Dirs { vec4 dirs[]; };
layout(std430, binding = 1) writeonly buffer Decoded { vec4 decoded[]; };
layout(binding = 0, r32ui) uniform uimage2D encoded; /* the G-buffer's normal format */

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(dirs.length())) return;
    int width = imageSize(encoded).x;
    ivec2 texel = ivec2(int(i) % width, int(i) / width);
    imageStore(encoded, texel, uvec4(packUnorm2x16(octahedral_encode(dirs[i].xyz)), 0u, 0u, 0u));
    memoryBarrierImage();
    /* Read back through the unorm16 quantisation (same invocation, same texel). */
    vec2 q = unpackUnorm2x16(imageLoad(encoded, texel).r);
    decoded[i] = vec4(octahedral_decode(q), 0.0);
}
