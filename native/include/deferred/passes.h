// The render passes the renderer can produce, with Cycles' names, channel ids
// and background values (shared/REFERENCE.md section 1).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace deferred {

enum class Pass : std::uint32_t {
    Combined = 0,  // RGBA: lit colour, alpha = coverage (0 on background if film transparent)
    Depth,         // Z: positive camera-space Z (planar), background 1e10
    Mist,          // Z: Blender mist factor from ray distance, background 1
    Position,      // XYZ: world space, background 0
    Normal,        // XYZ: world space shading normal, background 0
    UV,            // UVA: active UV map, A = 1 on geometry
    IndexOB,       // X: object pass index
    IndexMA,       // X: material pass index
    DiffDir,       // RGB: diffuse direct light divided by DiffCol
    DiffCol,       // RGB: diffuse albedo base*(1-metallic) (+ sheen weight)
    GlossDir,      // RGB: glossy direct light divided by GlossCol
    GlossCol,      // RGB: glossy closure weight
    Emit,          // RGB: emission
    Env,           // RGB: world colour where the background is seen
    Shadow,        // RGB: shadowed / unshadowed direct light (luminance; 1 = unshadowed), as
                   // EEVEE's Shadow pass (Cycles 3.x has none); 1 on background and unlit pixels
    AO,            // RGB: ambient occlusion, the cosine-weighted visible fraction of the
                   // hemisphere (occluders at any distance), background 0
    Vector,        // XYZW: screen-space motion in pixels, Cycles' convention (primitive_motion_vector):
                   // xy = raster(previous frame) - raster(now), zw = raster(now) - raster(next frame),
                   // averaged over the samples that hit a surface; background 0. Needs the motion
                   // the caller gives (instances, camera, deforming meshes); none: 0
    ShadowCatcher, // RGB: Cycles' Shadow Catcher pass (film_calculate_shadow_catcher): at shadow
                   // catcher objects their light with every shadow over their light without the
                   // other objects, alpha-over on white; 1 elsewhere. Asked for, Combined holds the
                   // catchers as holes (the matte); not asked for, Combined carries their shadow
                   // in alpha (Cycles' approximate shadow catcher)
    Count
};

constexpr std::uint32_t kPassCount = static_cast<std::uint32_t>(Pass::Count);

struct PassInfo {
    Pass pass;
    const char* name;     // Blender's pass name ("Combined", "Depth", ...)
    const char* chan_id;  // Blender's channel ids ("RGBA", "Z", "XYZ", ...)
    int channels;
    float background[4];  // value where no geometry is seen
};

const PassInfo& pass_info(Pass pass);
std::optional<Pass> pass_from_name(const std::string& name);

// A set of passes as a bit mask (bit i = Pass(i)).
class PassSet {
public:
    PassSet() = default;
    PassSet(std::initializer_list<Pass> passes) {
        for (Pass p : passes) insert(p);
    }
    void insert(Pass p) { bits_ |= 1u << static_cast<std::uint32_t>(p); }
    bool contains(Pass p) const { return (bits_ >> static_cast<std::uint32_t>(p)) & 1u; }
    std::uint32_t bits() const { return bits_; }
    std::vector<Pass> list() const;

private:
    std::uint32_t bits_ = 1u;  // Combined is always produced
};

}  // namespace deferred
