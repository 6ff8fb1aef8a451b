#include <deferred/passes.h>

#include "../../shaders/shader_defines.h"

#include <array>

namespace deferred {

// The shader's PASS_* ids are the enum's values.
static_assert(PASS_COMBINED == int(Pass::Combined) && PASS_DEPTH == int(Pass::Depth) &&
              PASS_MIST == int(Pass::Mist) && PASS_POSITION == int(Pass::Position) &&
              PASS_NORMAL == int(Pass::Normal) && PASS_UV == int(Pass::UV) &&
              PASS_INDEX_OB == int(Pass::IndexOB) && PASS_INDEX_MA == int(Pass::IndexMA) &&
              PASS_DIFF_DIR == int(Pass::DiffDir) && PASS_DIFF_COL == int(Pass::DiffCol) &&
              PASS_GLOSS_DIR == int(Pass::GlossDir) && PASS_GLOSS_COL == int(Pass::GlossCol) &&
              PASS_EMIT == int(Pass::Emit) && PASS_ENV == int(Pass::Env) && PASS_SHADOW == int(Pass::Shadow) &&
              PASS_AO == int(Pass::AO) && PASS_VECTOR == int(Pass::Vector) &&
              PASS_SHADOW_CATCHER == int(Pass::ShadowCatcher) && kPassCount == 18,
              "shader_defines.h PASS_* ids drifted from deferred::Pass");

namespace {
const std::array<PassInfo, kPassCount> kPasses = {{
    {Pass::Combined, "Combined", "RGBA", 4, {0, 0, 0, 0}},
    {Pass::Depth, "Depth", "Z", 1, {1e10f, 0, 0, 0}},
    {Pass::Mist, "Mist", "Z", 1, {1, 0, 0, 0}},
    {Pass::Position, "Position", "XYZ", 3, {0, 0, 0, 0}},
    {Pass::Normal, "Normal", "XYZ", 3, {0, 0, 0, 0}},
    {Pass::UV, "UV", "UVA", 3, {0, 0, 0, 0}},
    {Pass::IndexOB, "IndexOB", "X", 1, {0, 0, 0, 0}},
    {Pass::IndexMA, "IndexMA", "X", 1, {0, 0, 0, 0}},
    {Pass::DiffDir, "DiffDir", "RGB", 3, {0, 0, 0, 0}},
    {Pass::DiffCol, "DiffCol", "RGB", 3, {0, 0, 0, 0}},
    {Pass::GlossDir, "GlossDir", "RGB", 3, {0, 0, 0, 0}},
    {Pass::GlossCol, "GlossCol", "RGB", 3, {0, 0, 0, 0}},
    {Pass::Emit, "Emit", "RGB", 3, {0, 0, 0, 0}},
    {Pass::Env, "Env", "RGB", 3, {0, 0, 0, 0}},
    {Pass::Shadow, "Shadow", "RGB", 3, {1, 1, 1, 0}},
    {Pass::AO, "AO", "RGB", 3, {0, 0, 0, 0}},
    {Pass::Vector, "Vector", "XYZW", 4, {0, 0, 0, 0}},
    {Pass::ShadowCatcher, "Shadow Catcher", "RGB", 3, {1, 1, 1, 0}},
}};
}  // namespace

const PassInfo& pass_info(Pass pass) { return kPasses[static_cast<std::size_t>(pass)]; }

std::optional<Pass> pass_from_name(const std::string& name) {
    for (const PassInfo& p : kPasses)
        if (name == p.name) return p.pass;
    return std::nullopt;
}

std::vector<Pass> PassSet::list() const {
    std::vector<Pass> out;
    for (std::uint32_t i = 0; i < kPassCount; ++i)
        if (contains(Pass(i))) out.push_back(Pass(i));
    return out;
}

}  // namespace deferred
