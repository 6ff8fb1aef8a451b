/* Structs the GPU reads, compiled both as C++ (native/) and as GLSL (shaders/).
 *
 * Every member is a vec4/uvec4/mat4 so that std140 and std430 layouts equal
 * the C++ layout with no hidden padding; the static asserts below pin the
 * sizes. Positions are camera-relative (the camera position is subtracted in
 * double on the CPU), so float32 keeps sub-millimetre precision even when the
 * scene sits 1e6 m from the origin. */
#ifndef DEFERRED_SHADER_SHARED_H
#define DEFERRED_SHADER_SHARED_H

#ifdef __cplusplus
#include <cstdint>
namespace deferred::gpu {
struct alignas(16) vec4 { float x, y, z, w; };
struct alignas(16) uvec4 { std::uint32_t x, y, z, w; };
struct alignas(16) mat4 { vec4 cols[4]; };
#define SHARED_STRUCT(name) struct alignas(16) name
#define SHARED_ASSERT_SIZE(name, bytes) static_assert(sizeof(name) == (bytes) && alignof(name) == 16, #name " layout drifted")
#else
#define SHARED_STRUCT(name) struct name
#define SHARED_ASSERT_SIZE(name, bytes)
#endif

/* Light types (GpuLight.position_type.w) and area shapes (GpuLight.axis_y.w). */
#define LIGHT_POINT 0
#define LIGHT_SPOT 1
#define LIGHT_SUN 2
#define LIGHT_AREA 3
#define LIGHT_MESH 4 /* an emissive mesh instance (emitter_module.h) */
#define AREA_RECT 0
#define AREA_ELLIPSE 1

/* One light, in camera-relative world space.
 *   position_type : xyz position, w = LIGHT_* type
 *   strength      : rgb = colour x energy (S, Watts; sun W/m^2), w = sphere radius R (point/spot)
 *                   or the sun's angular radius (angle/2)
 *   direction     : xyz = the light's -Z axis (unit), w = cos(spot_size/2)
 *   axis_x        : xyz = area half-extent along the light's X axis (size/2 x X scale), w = spot blend width (1-cs)*blend;
 *                   sun: w = tan of the angular radius (computed in double, capped at 1e7)
 *   axis_y        : xyz = area half-extent along the light's Y axis, w = AREA_* shape; sun: w = cos of the
 *                   angular radius
 *   params        : x = area A (m^2, pi/4 factor for ellipses), y = cast shadow (0/1),
 *                   z = influence radius (m) beyond which the light is culled, < 0: infinite
 *                   (sun), w = index of its GpuShadow, or -1 without shadow maps this frame */
SHARED_STRUCT(GpuLight) {
    vec4 position_type;
    vec4 strength;
    vec4 direction;
    vec4 axis_x;
    vec4 axis_y;
    vec4 params;
};
SHARED_ASSERT_SIZE(GpuLight, 96);
/* An emissive mesh's light (LIGHT_MESH) reuses GpuLight:
 *   position_type : xyz its bounding sphere's centre (culling), w LIGHT_MESH
 *   strength      : rgb the radiance at this sample's shared point, w 0
 *   direction     : x first triangle in the emitter buffer, y triangle count, z total area,
 *                   w its bounding sphere's radius
 *   axis_x        : xyz this sample's shared point (its cube shadow map looks from it),
 *                   w its density (area measure) under the light's CDF
 *   axis_y        : xyz the unit (winding) normal of the shared point's triangle, w the side
 *                   that emits: 0 both (an open mesh), +1 / -1 along / against the winding
 *                   normal (a closed mesh: its other side faces its inside)
 *   params        : as for the other lights (z influence radius, w shadow index) */

/* One emitting triangle (camera-relative) of a mesh light.
 *   v0       : xyz vertex 0, w the light's CDF after this triangle (the last is 1)
 *   e1, e2   : xyz edges v1 - v0, v2 - v0; e1.w its area, e2.w its probability
 *   radiance : rgb emitted radiance (two-sided); w 0, or for a textured emitter its tile
 *              + 1 among the baked texels (light_lib.glsl emitter_radiance) */
SHARED_STRUCT(GpuEmitterTriangle) {
    vec4 v0;
    vec4 e1;
    vec4 e2;
    vec4 radiance;
};
SHARED_ASSERT_SIZE(GpuEmitterTriangle, 64);

/* One material (Blender 3.4 Principled BSDF constants).
 *   base_diffuse : rgb base colour, a diffuse model: < 0 the Principled BSDF's
 *                  (Burley), >= 0 a Diffuse BSDF: Oren-Nayar with this sigma (0: Lambert)
 *   params0    : metallic, roughness, specular, specular_tint
 *   params1    : sheen, sheen_tint, clearcoat, clearcoat_roughness
 *   emission   : rgb emission colour x strength, w = material pass index
 *   mix        : x material id taken instead with probability y (stochastic Mix Shader),
 *                x < 0: none; z offset of a node material's constants in the constants
 *                buffer; w alpha (coverage: transparency_random) */
SHARED_STRUCT(GpuMaterial) {
    vec4 base_diffuse;
    vec4 params0;
    vec4 params1;
    vec4 emission;
    vec4 mix;
};
SHARED_ASSERT_SIZE(GpuMaterial, 80);

/* One mesh instance.
 *   model         : object -> camera-relative world
 *   normal_matrix : inverse transpose of model's 3x3 (w column unused)
 *   ids           : x object pass index, y offset of its material slot map in
 *                   the slot buffer, z slot count, w flags: 1 mirrored (negative
 *                   determinant), 2 holdout (Object > Visibility > Holdout)
 *   color         : Object > Viewport Display colour (Object Info Color, Alpha)
 *   info          : x Object Info Random (Cycles' per-object/per-instance value), y Shadow
 *                   Terminator Geometry Offset (shadow_lib.glsl shadow_ray_origin), zw unused */
SHARED_STRUCT(GpuInstance) {
    mat4 model;
    mat4 normal_matrix;
    uvec4 ids;
    vec4 color;
    vec4 info;
};
SHARED_ASSERT_SIZE(GpuInstance, 176);

/* Per-frame constants (std140 uniform block FrameBlock).
 *   view            : camera-relative world -> view (rotation only)
 *   projection      : view -> clip, reversed Z (near -> 1, far -> 0)
 *   inv_view, inv_projection
 *   camera_position : xyz world position of the camera (for the Position pass), w = 1 if orthographic
 *   world_color     : rgb world colour, w = 1 if film transparent
 *   viewport        : width, height, 1/width, 1/height
 *   mist            : start, 1/depth, falloff (0 quadratic, 1 linear, 2 inverse quadratic), unused
 *   counts          : x light count, y requested pass bits, z light-shape points K per sample, w samples
 *   sample_shift    : xy this sample's point in [0,1)^2 inside every cell of the light-shape
 *                     grid and on the sun's disk (0.5: the centre, sample 0), z the
 *                     sample's point of the 1D golden-ratio sequence (stochastic material
 *                     mixes, rotated per pixel), w the sample's index (transparency_random)
 *   tiles           : x tiles per row, y tile rows, z 1 if light culling is on, w the pixel
 *                     filter's reach in whole pixels (tile frusta are widened by it)
 *   world_occlusion : x index (GpuShadow) of this sample's first world-occlusion map, < 0
 *                     without one; y the number of maps (consecutive indices); zw the world
 *                     map's width and height (world_lib.glsl; 0 for a constant world)
 *   jitter          : xy this sample's pixel-filter offset in NDC (added by projection), z the
 *                     camera's clip start, w the share of a directly seen emission each sample
 *                     or emission sub-sample adds (1/K, emission_samples.h; 1 without them)
 *   motion          : motion blur (motion_module.h): xyz this sample's camera position relative
 *                     to the frame's (camera-relative positions keep the frame's origin; view
 *                     includes the translation), w the sample's relative shutter time in
 *                     [-1, 1] (deforming meshes); all 0 without motion blur */
SHARED_STRUCT(FrameConstants) {
    mat4 view;
    mat4 projection;
    mat4 inv_view;
    mat4 inv_projection;
    vec4 camera_position;
    vec4 world_color;
    vec4 viewport;
    vec4 mist;
    uvec4 counts;
    vec4 sample_shift;
    uvec4 tiles;
    vec4 world_occlusion;
    vec4 jitter;
    vec4 motion;
};
SHARED_ASSERT_SIZE(FrameConstants, 416);

/* One shadow-casting light's maps for the current film sample.
 *   point         : xyz the sample's point on the light (camera-relative), w first layer in the
 *                   shadow map array
 *   params        : x kind (SHADOW_CUBE: 6 layers, +X -X +Y -Y +Z -Z; SHADOW_CASCADES: 4 layers;
 *                   SHADOW_WORLD: point.xyz the direction light travels from the world, w its
 *                   layer of the world's own array (TEX_WORLD_MAP)),
 *                   y this light's map resolution (texels per side), z texel size at unit
 *                   distance (cube: 2 overlap/res; world: the density p(w) + p(-w) its
 *                   direction pair was drawn with), w resolution / the array's layer size
 *                   (the maps fill the lower-left corner of their layers)
 *   cascade_split : cascades: far view depth of cascades 0..3; cubes: xy the sample's
 *                   offset on the sphere light's disk, along each face's right/up axes, z
 *                   occluders nearer the point than this are no shadow (an emissive mesh's
 *                   own surface around its point; 0 for lights)
 *   cascade       : camera-relative world -> cascade clip space (orthographic, depth in [0,1]
 *                   along the sun's direction, 1 nearest the sun) */
#define SHADOW_CUBE 0
#define SHADOW_CASCADES 1
#define SHADOW_WORLD 2 /* one orthographic map (cascade[0]) along a direction of the world */
#define SHADOW_CASCADE_COUNT 4
/* Cube faces cover tan(angle) <= 1.1 instead of 1 (a little more than 90
 * degrees) so points near a face border are inside the face as seen from
 * any of the sample's per-face light points. */
#define SHADOW_CUBE_OVERLAP 1.1
SHARED_STRUCT(GpuShadow) {
    vec4 point;
    vec4 params;
    vec4 cascade_split;
    mat4 cascade[4];
};
SHARED_ASSERT_SIZE(GpuShadow, 304);

/* One screen tile's light list, written by light_cull_comp.glsl.
 *   list  : x offset of the tile's light indices in the index buffer, y count,
 *           z 2.5D depth mask (bit i: some pixel of the tile lies in depth bin i
 *           of [depth.x, depth.y]), w 1 if the tile has geometry
 *   depth : x, y nearest/farthest positive view depth of the tile's pixels
 *           (widened by the pixel filter's reach), zw unused */
SHARED_STRUCT(GpuTile) {
    uvec4 list;
    vec4 depth;
};
SHARED_ASSERT_SIZE(GpuTile, 32);

#ifdef __cplusplus
}  // namespace deferred::gpu
#endif

#endif
