/* Every binding slot and workgroup size, shared by C++ and GLSL, so the two
 * sides cannot disagree on where a buffer or image lives. */
#ifndef DEFERRED_SHADER_DEFINES_H
#define DEFERRED_SHADER_DEFINES_H

/* Uniform blocks */
#define UBO_FRAME 0

/* Shader storage buffers */
#define SSBO_POSITIONS 0
#define SSBO_INDICES 1
#define SSBO_NORMALS 2
#define SSBO_UVS 3
#define SSBO_MATERIAL_INDICES 4
#define SSBO_INSTANCES 5
#define SSBO_MATERIAL_SLOTS 6
#define SSBO_MATERIALS 7
#define SSBO_LIGHTS 8
#define SSBO_TILES 9
#define SSBO_TILE_LIGHTS 10
#define SSBO_CULL_COUNTER 11
#define SSBO_SHADOWS 12
#define SSBO_INSTANCE_REMAP 13 /* shadow maps: the instances left after culling, per draw */
#define SSBO_MATERIAL_CONSTANTS 14 /* node materials: per-material constants (material_lib.glsl) */
#define SSBO_ATTRIBUTES 15     /* node materials: the mesh's named per-corner attributes */
#define SSBO_WORLD_CDF 16      /* the world map's sampling CDFs (world_lib.glsl) */
#define SSBO_EMITTERS 17       /* emissive meshes' triangles (GpuEmitterTriangle, emitter_module.h) */
#define SSBO_CRYPTO_INSTANCES 18 /* Cryptomatte: object and asset hash per instance (cryptomatte_module.h) */
#define SSBO_CRYPTO_MATERIALS 19 /* ... the material's name hash per material id */
#define SSBO_CRYPTO_SLOTS 20     /* ... per pixel and layer, Levels (hash, coverage bits) slots */
#define SSBO_LIGHT_GROUPS 21     /* light groups: each packed light's group, 0 none (light_module.h) */
#define SSBO_INSTANCE_GROUPS 22  /* ... each instance's group, for its emission */
#define SSBO_EMISSION_TEXELS 23   /* textured emitters' baked radiance (emitter_module.h) */
#define SSBO_RAY_SCENE 24         /* shadow rays' hierarchies and triangles (ray_scene.h, ray_lib.glsl) */
#define SSBO_INSTANCE_MOTION 25   /* Vector pass: each instance's previous and next model matrix (motion_module.h) */
#define SSBO_MOTION_POSITIONS 26  /* ... a deforming mesh's previous, then next vertex positions */
#define SSBO_RECEIVERS 27         /* shadow map sizing: sample 0's depth range and grid (receivers_comp.glsl) */
#define SSBO_VIS_KEYS 28          /* visibility buffer: per slot key, its indirect dispatch, count, offset, cursor */
#define SSBO_VIS_TILES 29         /* ... the screen tiles where each key appears, grouped by key (visibility_classify_comp.glsl) */
#define SSBO_LIGHTING_LATER 30    /* lighting: the pixels whose light sequence goes on past the first batch, and their indirect dispatch */

/* Textures sampled by compute passes (G-buffer inputs) */
#define TEX_DEPTH 0
#define TEX_GBUF_BASE 1
#define TEX_GBUF_PARAMS0 2
#define TEX_GBUF_NORMAL 3
#define TEX_GBUF_PARAMS1 4
#define TEX_GBUF_IDS 5
#define TEX_GBUF_UV 6
#define TEX_GBUF_EMISSION 7
#define TEX_DIFF_LIGHT 8
#define TEX_GLOSS_LIGHT 9
#define TEX_SHADOW_MAPS 10
#define TEX_SHADOW_LIGHT 11
#define TEX_WORLD_MAP 12    /* RG32F array: (-nearest, farthest) depth along each world direction */
#define TEX_GBUF_GEOMETRY 13
#define TEX_WORLD_RADIANCE 14 /* RGBA32F equirectangular: the world's radiance for light (world_lib.glsl) */
#define TEX_WORLD_CAMERA 15   /* ... as camera rays see it (differs with Light Path Is Camera Ray) */
/* The forward pass's layer (rgb light, a transmittance) read by the lighting
 * pass; the unit is TEX_SHADOW_LIGHT's, which only the Shadow resolve reads,
 * after the sample loop (units from 16 on are the materials' images). */
#define TEX_FORWARD_LAYER 11
/* The Vector pass's sample count per pixel, read by its resolve after the
 * sample loop: TEX_SHADOW_LIGHT's unit again, in a dispatch of its own. */
#define TEX_MOTION_WEIGHT 11
/* The shadow catcher's resolves (after the sample loop, dispatches of their
 * own): its shadowed and unshadowed light, and the film. */
#define TEX_CATCHER_HIT 8
#define TEX_CATCHER_PASS 9
#define TEX_CATCHER_FILM 11
/* The visibility buffer (instance, triangle, slot key + 1), read by the
 * G-buffer's resolve (gbuffer_resolve_comp.glsl), which runs before any
 * pass that binds TEX_DIFF_LIGHT's unit. */
#define TEX_VISIBILITY 8
/* Node materials: image slot k of the drawn material at unit TEX_MATERIAL_IMAGE0 + k */
#define TEX_MATERIAL_IMAGE0 16

/* Images written by compute passes */
#define IMG_FILM 0        /* Combined accumulation */
#define IMG_DIFF_LIGHT 1  /* diffuse direct light, with albedo (divided later) */
#define IMG_GLOSS_LIGHT 2
#define IMG_PASS_OUT 3
#define IMG_SHADOW 4      /* x shadowed, y unshadowed direct-light luminance (Shadow pass) */
#define IMG_AO 5          /* AO pass accumulation (lighting pass, first batch) */
#define IMG_WORLD_BAKE 6  /* the world map being baked (world_bake_comp.glsl) */
#define IMG_LIGHT_GROUPS 7 /* light groups: one layer of accumulated light per group (rgba32f array) */
/* Shadow catchers (lighting pass, SHADOW_CATCHER): at catcher pixels the light
 * with every shadow (rgb) and the samples' share (a), and the light the
 * catcher would get without the other objects (rgb). Bindings of images the
 * lighting pass does not otherwise use (the pass images and the world bake). */
#define IMG_CATCHER_HIT 3
#define IMG_CATCHER_PASS 6
/* The film's splat (film_splat_comp.glsl, a dispatch of its own after each
 * sample): this sample's values, and the accumulation they are added to. */
#define IMG_SPLAT_SAMPLE 0
#define IMG_SPLAT_FILM 1
/* ... its uniforms: the taps' first offsets and counts (x, y, count x,
 * count y), the edge margin, then each axis's weights (SPLAT_MAX_TAPS each;
 * film.h kMaxSplatTaps) */
#define LOC_SPLAT_TAPS 0
#define LOC_SPLAT_MARGIN 1
#define LOC_SPLAT_WEIGHTS_X 2
#define SPLAT_MAX_TAPS 8
#define LOC_SPLAT_WEIGHTS_Y (LOC_SPLAT_WEIGHTS_X + SPLAT_MAX_TAPS)

/* The world map's sampling density: this fraction uniform on the sphere, the
 * rest by luminance (defensive importance sampling: every direction keeps a
 * density, which bounds the occlusion estimate where the map is dark). */
#define WORLD_UNIFORM_FRACTION 0.2
/* Directions per pixel and film sample for the world's unoccluded light:
 * this many from the map and as many from the BSDF (multiple importance). */
#define WORLD_LIGHT_SAMPLES 2
/* Shadow maps (shadow_lib.glsl): the bias left by the receiver-plane
 * comparison, in texels, and the smallest |cos| between the receiver's plane
 * and a map's ray for which that comparison is used. */
#define SHADOW_PLANE_BIAS 0.5
#define SHADOW_PLANE_MIN_COS 0.01
/* Points per pixel and film sample on each emissive mesh light. */
#define MESH_LIGHT_SAMPLES 2
#define MESH_LIGHT_SAMPLES_NEAR 8 /* ... within twice its bounding radius */
/* Directions of a sharp specular lobe per pixel and film sample traced against
 * the triangles of a mesh light with at most MESH_LIGHT_TRACED_TRIANGLES of
 * them (multiple importance with its points), and a mirror's reflected ray
 * (light_lib.glsl). A light of more than MESH_LIGHT_CHUNK triangles is met
 * chunk by chunk: each run of MESH_LIGHT_CHUNK triangles has a bounding
 * sphere (EmitterModule), at most MESH_LIGHT_TRACED_TRIANGLES /
 * MESH_LIGHT_CHUNK chunk tests and MESH_LIGHT_CHUNK triangles per chunk met
 * (llvmpipe's 65535 loop iterations an invocation: LightingStage sizes its
 * batches with this). */
#define MESH_LIGHT_BSDF_SAMPLES 2
#define MESH_LIGHT_CHUNK 64
#define MESH_LIGHT_TRACED_TRIANGLES 4096
/* Shadow rays (ray_scene.h, ray_lib.glsl): levels of a hierarchy at most
 * (the traversal's stack depth), and node visits per ray at most (llvmpipe
 * ends all loops of an invocation after 65535 iterations: lighting batches
 * are sized with this; a ray past it counts as unblocked). */
#define RAY_MAX_DEPTH 48
#define RAY_MAX_STEPS 4096

/* Fragment outputs of the geometry pass (G-buffer MRT) */
#define OUT_EMISSION 0
#define OUT_BASE 1
#define OUT_PARAMS0 2
#define OUT_NORMAL 3
#define OUT_PARAMS1 4
#define OUT_IDS 5
#define OUT_UV 6
#define OUT_GEOMETRY 7

/* The visibility buffer's classification and resolve (visibility_module.h):
 * uints per slot key in SSBO_VIS_KEYS (a DispatchIndirectCommand, then the
 * key's tile count, first index in SSBO_VIS_TILES, and fill cursor), the
 * tile (the resolve's workgroup: VIS_TILE^2 pixels), the workgroups per row
 * of its dispatch, and its uniforms naming the key it resolves and the
 * number of keys. */
#define VIS_KEY_STRIDE 8
#define VIS_KEY_COUNT 3
#define VIS_KEY_OFFSET 4
#define VIS_KEY_CURSOR 5
#define VIS_TILE 8
#define VIS_SCAN_SIZE 256
#define VIS_DISPATCH_ROW 32768
#define LOC_VIS_KEY 40
#define LOC_VIS_KEY_COUNT 41

/* Shadow maps: the half-spaces a cube face's casters are clipped to
 * (geometry_vert.glsl SHADOW_PASS, gl_ClipDistance; ShadowModule's lit
 * region), SHADOW_CLIP_PLANES vec4s from LOC_SHADOW_CLIP on. */
#define SHADOW_CLIP_PLANES 4
#define LOC_SHADOW_CLIP 42
/* The visibility buffer drawn by vertex (visibility_frag.glsl
 * INDEXED_DRAW): the drawn range's first triangle, to which gl_PrimitiveID
 * counts (after LOC_SHADOW_CLIP's SHADOW_CLIP_PLANES locations). */
#define LOC_FIRST_TRIANGLE 46

/* Pass ids (deferred::Pass; static_assert'ed in native/src/passes.cpp) */
#define PASS_COMBINED 0
#define PASS_DEPTH 1
#define PASS_MIST 2
#define PASS_POSITION 3
#define PASS_NORMAL 4
#define PASS_UV 5
#define PASS_INDEX_OB 6
#define PASS_INDEX_MA 7
#define PASS_DIFF_DIR 8
#define PASS_DIFF_COL 9
#define PASS_GLOSS_DIR 10
#define PASS_GLOSS_COL 11
#define PASS_EMIT 12
#define PASS_ENV 13
#define PASS_SHADOW 14
#define PASS_AO 15
#define PASS_VECTOR 16
#define PASS_SHADOW_CATCHER 17

/* Compute workgroup size (8x8 pixels) */
#define LIGHTING_GROUP_SIZE 8
/* Light-culling tiles: TILE_SIZE x TILE_SIZE pixels, one workgroup each; the
 * 2.5D depth mask has 32 bins (Harada 2012) */
#define TILE_SIZE 16
#define DEPTH_BINS 32

#endif
