// Cryptomatte (cryptomatte_module.h): ids as Cycles' floats, coverage per
// film sample, ranked per pixel.
#include "cryptomatte_module.h"

#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

using namespace deferred;
using namespace deferred::testing;

namespace {
std::uint32_t bits(float f) {
    std::uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}
}  // namespace

TEST(Cryptomatte, HashToFloatIsCycles) {
    // A normal float keeps its bits (SphereB's hash in Cycles' own EXR).
    EXPECT_EQ(bits(cryptomatte_hash_to_float(0x89000f97u)), 0x89000f97u);
    // Exponent 0 and 255 (denormal, inf/NaN) are clamped to 1 and 254.
    EXPECT_EQ(bits(cryptomatte_hash_to_float(0x00000005u)), 0x00800005u);
    EXPECT_EQ(bits(cryptomatte_hash_to_float(0xFF812345u)), 0xFF012345u);
}

TEST(Cryptomatte, CoverageSplitsAtEdgesAndIsRankedPerPixel) {
    // Two planes meeting along x = 0 (object hashes 11 and 22, material
    // hashes 33 and 44) over a black world, seen from above; pixel centres
    // straddle the seam. Interior pixels: one id with coverage 1; seam
    // pixels: two ids whose coverages add up to 1, the larger first;
    // outside both planes nothing.
    Renderer r;
    set_world_color(r, 0, 0, 0);
    tools::MeshArrays plane = tools::make_plane(1.0f, 1);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    Material a, b;
    a.crypto = 33;
    b.crypto = 44;
    const std::uint32_t ma = r.add_material(a), mb = r.add_material(b);
    const Mat4d left = tools::translation(-1.0, 0, 0), right = tools::translation(1.0, 0, 0);
    const std::uint32_t ids_a[2] = {11, 111}, ids_b[2] = {22, 222};
    r.add_instances(mesh, left.data(), 1, nullptr, {ma}, true, nullptr, nullptr, ids_a);
    r.add_instances(mesh, right.data(), 1, nullptr, {mb}, true, nullptr, nullptr, ids_b);
    RenderSettings s;
    s.width = 33;  // odd: the seam runs through the middle column
    s.height = 8;
    s.samples = 64;
    s.cryptomatte = {CryptomatteKind::Object, CryptomatteKind::Material, CryptomatteKind::Asset};
    s.cryptomatte_levels = 4;
    FrameResult f = r.render(top_down_ortho(5.0, 4.4f), s);  // 4.4 m wide: 0.2 m beyond each plane's edge
    ASSERT_EQ(f.cryptomatte.size(), 3u);
    const CryptomatteImage& obj = f.cryptomatte[0];
    ASSERT_EQ(obj.kind, CryptomatteKind::Object);
    ASSERT_EQ(obj.levels, 4);
    auto at = [&](const CryptomatteImage& img, int x, int y, int rank) {
        const float* p = &img.pixels[(std::size_t(y) * img.width + x) * img.levels * 2 + rank * 2];
        return std::pair<std::uint32_t, float>(bits(p[0]), p[1]);
    };
    const int y = 4;
    EXPECT_EQ(at(obj, 8, y, 0).first, bits(cryptomatte_hash_to_float(11)));
    EXPECT_NEAR(at(obj, 8, y, 0).second, 1.0f, 1e-5);
    EXPECT_EQ(at(obj, 8, y, 1).second, 0.0f);
    EXPECT_EQ(at(f.cryptomatte[1], 8, y, 0).first, bits(cryptomatte_hash_to_float(33)));
    EXPECT_EQ(at(f.cryptomatte[2], 24, y, 0).first, bits(cryptomatte_hash_to_float(222)));
    // The seam column: both ids, ranked, summing to 1.
    const auto first = at(obj, 16, y, 0), second = at(obj, 16, y, 1);
    EXPECT_GT(first.second, 0.2f);
    EXPECT_GT(second.second, 0.2f);
    EXPECT_GE(first.second, second.second);
    EXPECT_NEAR(first.second + second.second, 1.0f, 1e-5);
    EXPECT_NE(first.first, second.first);
    // Beyond the planes (the outermost column sees background only).
    EXPECT_EQ(at(obj, 0, y, 0).second, 0.0f);
    EXPECT_EQ(at(obj, 0, y, 0).first, 0u);
}

TEST(Cryptomatte, EveryPixelOfAFrameLargerThanOneRankingChunkIsRanked) {
    // The ranking runs in chunks of 16384 pixels on several threads
    // (CryptomatteModule::finish): 257 x 80 = 20560 pixels span two. The
    // two planes of the test above, seen whole: every pixel inside a plane
    // (3 pixels from its edges) has its id first with coverage 1, every
    // pixel beyond both has nothing, and every pixel's levels are ranked.
    Renderer r;
    set_world_color(r, 0, 0, 0);
    tools::MeshArrays plane = tools::make_plane(1.0f, 1);
    const std::uint32_t mesh = r.add_mesh(plane.view());
    const std::uint32_t mat = r.add_material(Material{});
    const Mat4d left = tools::translation(-1.0, 0, 0), right = tools::translation(1.0, 0, 0);
    const std::uint32_t ids_a[2] = {11, 111}, ids_b[2] = {22, 222};
    r.add_instances(mesh, left.data(), 1, nullptr, {mat}, true, nullptr, nullptr, ids_a);
    r.add_instances(mesh, right.data(), 1, nullptr, {mat}, true, nullptr, nullptr, ids_b);
    RenderSettings s;
    s.width = 257;
    s.height = 80;  // 1.37 m of the planes' 2 m: every row crosses both
    s.samples = 4;
    s.cryptomatte = {CryptomatteKind::Object};
    s.cryptomatte_levels = 2;
    const FrameResult f = r.render(top_down_ortho(5.0, 4.4f), s);
    ASSERT_EQ(f.cryptomatte.size(), 1u);
    const CryptomatteImage& obj = f.cryptomatte[0];
    const float id_a = cryptomatte_hash_to_float(11), id_b = cryptomatte_hash_to_float(22);
    const double pixel_m = 4.4 / s.width, margin = 3 * pixel_m;
    int inside = 0, outside = 0, unranked = 0, wrong = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            const float* p = &obj.pixels[(std::size_t(y) * std::size_t(s.width) + std::size_t(x)) * 4];
            if (p[1] < p[3]) ++unranked;
            const double cx = -2.2 + (x + 0.5) * pixel_m;  // the pixel centre's x in metres
            if (std::abs(cx) > 2.0 + margin) {
                ++outside;
                if (p[0] != 0.0f || p[1] != 0.0f) ++wrong;
            } else if (std::abs(cx) < 2.0 - margin && std::abs(cx) > margin) {
                ++inside;
                if (bits(p[0]) != bits(cx < 0 ? id_a : id_b) || std::abs(p[1] - 1.0f) > 1e-5f || p[3] != 0.0f) ++wrong;
            }
        }
    EXPECT_GT(inside, 15000);
    EXPECT_GT(outside, 500);
    EXPECT_EQ(unranked, 0);
    EXPECT_EQ(wrong, 0);
}

TEST(Cryptomatte, NothingAskedNothingMade) {
    Renderer r;
    add_plane(r, Material{});
    RenderSettings s;
    s.width = s.height = 8;
    FrameResult f = r.render(top_down_ortho(5.0, 4.0f), s);
    EXPECT_TRUE(f.cryptomatte.empty());
    s.cryptomatte = {CryptomatteKind::Object};
    s.cryptomatte_levels = 17;
    EXPECT_THROW(r.render(top_down_ortho(5.0, 4.0f), s), InvalidInput);
}

TEST(Cryptomatte, MoreIdsThanLevelsGoToTheLastSlotAsCycles) {
    // Three stripes (object hashes 1, 2, 3) side by side across the middle
    // pixel, Levels 2: Cycles' film_write_cryptomatte_slots adds a
    // third id's coverage to the last slot, so the pixel's coverage still
    // adds up to 1 (nothing is dropped).
    Renderer r;
    set_world_color(r, 0, 0, 0);
    tools::MeshArrays plane = tools::make_plane(0.05f, 1);
    MeshData data = plane.view();
    const std::uint32_t mesh = r.add_mesh(data);
    const std::uint32_t mat = r.add_material(Material{});
    for (int k = 0; k < 3; ++k) {
        // The middle stripe 0.1 m wide, the outer ones 0.9 m (beyond the
        // pixel filter's reach), all stretched along y over the image.
        Mat4d stripe = tools::translation(k == 1 ? 0.0 : (k == 0 ? -0.5 : 0.5), 0, 0);
        stripe[0] = k == 1 ? 1.0 : 9.0;
        stripe[5] = 100.0;
        const std::uint32_t ids[2] = {std::uint32_t(k + 1), 7};
        r.add_instances(mesh, stripe.data(), 1, nullptr, {mat}, true, nullptr, nullptr, ids);
    }
    RenderSettings s;
    s.width = 3;
    s.height = 1;
    s.samples = 64;
    s.cryptomatte = {CryptomatteKind::Object};
    s.cryptomatte_levels = 2;
    Camera cam = top_down_ortho(5.0, 0.9f);  // 0.3 m per pixel: the middle pixel spans the three stripes
    const FrameResult f = r.render(cam, s);
    const CryptomatteImage& obj = f.cryptomatte[0];
    const float* p = &obj.pixels[std::size_t(1) * obj.levels * 2];
    EXPECT_NEAR(p[1] + p[3], 1.0f, 1e-5);
    EXPECT_GT(p[3], 0.0f);
}
