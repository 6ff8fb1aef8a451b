#include "cryptomatte_module.h"

#include "parallel.h"
#include "shader_library.h"

#include "../../shaders/shader_defines.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace deferred {

const char* cryptomatte_name(CryptomatteKind kind) {
    switch (kind) {
        case CryptomatteKind::Object: return "CryptoObject";
        case CryptomatteKind::Material: return "CryptoMaterial";
        case CryptomatteKind::Asset: return "CryptoAsset";
    }
    return "Crypto";
}

float cryptomatte_hash_to_float(std::uint32_t hash) {
    // intern/cycles/util/hash.h, util_hash_to_float.
    const std::uint32_t mantissa = hash & ((1u << 23) - 1u);
    std::uint32_t exponent = (hash >> 23) & 0xFFu;
    exponent = std::min(std::max(exponent, 1u), 254u) << 23;
    const std::uint32_t sign = (hash >> 31) << 31;
    const std::uint32_t bits = sign | exponent | mantissa;
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

std::size_t CryptomatteModule::bytes(const RenderSettings& s) {
    if (s.cryptomatte.empty()) return 0;
    return std::size_t(s.width) * std::size_t(s.height) * s.cryptomatte.size() *
           std::size_t(std::clamp(s.cryptomatte_levels, 1, kMaxLevels)) * 8;
}

void CryptomatteModule::begin(const RenderSettings& s, const std::vector<std::uint32_t>& instance_hashes,
                              const std::vector<std::uint32_t>& material_hashes) {
    release();
    if (s.cryptomatte.empty()) return;
    if (s.cryptomatte.size() > 3) throw InvalidInput("cryptomatte: at most the three kinds (object, material, asset)");
    if (s.cryptomatte_levels < 1 || s.cryptomatte_levels > kMaxLevels)
        throw InvalidInput("cryptomatte_levels must be in 1.." + std::to_string(kMaxLevels) + ", got " +
                           std::to_string(s.cryptomatte_levels));
    kinds_ = s.cryptomatte;
    levels_ = s.cryptomatte_levels;
    width_ = s.width;
    height_ = s.height;
    slots_ = make_storage_buffer(nullptr, bytes(s), "cryptomatte slots");
    const std::uint32_t zero = 0;
    glClearNamedBufferData(slots_.get(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    const std::uint32_t none[2] = {0, 0};  // a buffer is never empty
    instances_ = instance_hashes.empty()
        ? make_storage_buffer(none, sizeof none, "cryptomatte instance hashes")
        : make_storage_buffer(instance_hashes.data(), instance_hashes.size() * 4, "cryptomatte instance hashes");
    materials_ = material_hashes.empty()
        ? make_storage_buffer(none, sizeof none, "cryptomatte material hashes")
        : make_storage_buffer(material_hashes.data(), material_hashes.size() * 4, "cryptomatte material hashes");
    check_gl("cryptomatte buffers");
}

void CryptomatteModule::accumulate(ShaderLibrary& shaders, int samples, unsigned groups_x, unsigned groups_y) {
    if (!active()) return;
    ShaderVariant v;
    v.defines.push_back("CRYPTO_LEVELS " + std::to_string(levels_));
    v.defines.push_back("CRYPTO_LAYERS " + std::to_string(kinds_.size()));
    for (std::size_t i = 0; i < 3; ++i)
        v.defines.push_back("CRYPTO_KIND_" + std::to_string(i) + " " +
                            std::to_string(i < kinds_.size() ? int(kinds_[i]) : 0));
    glUseProgram(shaders.compute_program("cryptomatte_comp.glsl", v));
    glUniform1f(0, 1.0f / float(samples));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_CRYPTO_INSTANCES, instances_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_CRYPTO_MATERIALS, materials_.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SSBO_CRYPTO_SLOTS, slots_.get());
    glDispatchCompute(groups_x, groups_y, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    check_gl("cryptomatte accumulation");
}

std::vector<CryptomatteImage> CryptomatteModule::finish() {
    std::vector<CryptomatteImage> out;
    if (!active()) return out;
    const std::size_t pixels = std::size_t(width_) * std::size_t(height_);
    const std::size_t layers = kinds_.size(), levels = std::size_t(levels_);
    // Copied on the GPU into a readback buffer and ranked straight from its
    // mapping, without a copy into a vector first.
    const std::size_t slot_bytes = pixels * layers * levels * 2 * sizeof(std::uint32_t);
    const Buffer staging = make_readback_buffer(slot_bytes, "cryptomatte slots");
    glCopyNamedBufferSubData(slots_.get(), staging.get(), 0, 0, GLsizeiptr(slot_bytes));
    check_gl("reading the cryptomatte slots");
    const auto* slots = static_cast<const std::uint32_t*>(map_for_reading(staging, slot_bytes, "cryptomatte slots"));
    struct Entry { std::uint32_t id; float coverage; };
    for (std::size_t layer = 0; layer < layers; ++layer) {
        CryptomatteImage img;
        img.kind = kinds_[layer];
        img.width = width_;
        img.height = height_;
        img.levels = levels_;
        img.pixels.assign(pixels * levels * 2, 0.0f);
        // Chunks of 16384 pixels ranked in parallel (parallel.h), each with its
        // own entries. The zero-fill above is still one thread's page faults.
        const std::size_t chunk = 16384, chunks = (pixels + chunk - 1) / chunk;
        parallel_for(chunks, [&](std::size_t c) {
            Entry entries[kMaxLevels];
            for (std::size_t p = c * chunk; p < std::min(pixels, (c + 1) * chunk); ++p) {
                const std::uint32_t* s = &slots[((p * layers) + layer) * levels * 2];
                for (std::size_t k = 0; k < levels; ++k) {
                    float coverage;
                    std::memcpy(&coverage, &s[2 * k + 1], sizeof coverage);
                    entries[k] = {s[2 * k], coverage};
                }
                // Most coverage first (Cycles' cryptomatte_post sorts the same
                // way), ties in slot order: an insertion sort of the few
                // levels, which std::stable_sort matched but with a buffer
                // allocated per pixel (malloc and free alone were 5 % of an
                // H200's 1.3 s per 1080p frame's CPU time).
                for (std::size_t k = 1; k < levels; ++k) {
                    const Entry e = entries[k];
                    std::size_t j = k;
                    for (; j > 0 && entries[j - 1].coverage < e.coverage; --j) entries[j] = entries[j - 1];
                    entries[j] = e;
                }
                float* o = &img.pixels[p * levels * 2];
                for (std::size_t k = 0; k < levels; ++k) {
                    if (!(entries[k].coverage > 0.0f)) break;  // empty slots stay (0, 0)
                    o[2 * k] = cryptomatte_hash_to_float(entries[k].id);
                    o[2 * k + 1] = entries[k].coverage;
                }
            }
        });
        out.push_back(std::move(img));
    }
    glUnmapNamedBuffer(staging.get());
    release();
    return out;
}

void CryptomatteModule::release() {
    slots_.reset();
    instances_.reset();
    materials_.reset();
    kinds_.clear();
}

}  // namespace deferred
