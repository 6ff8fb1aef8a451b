#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace deferred::tools {

void write_multilayer_exr(const std::string& path, const FrameResult& frame) {
    if (frame.passes.empty()) throw Error("write_multilayer_exr: no passes");
    const int w = frame.passes[0].width, h = frame.passes[0].height;
    Imf::Header header(w, h);
    Imf::FrameBuffer fb;
    // EXR rows go top-down; the passes are bottom-up: flip into copies.
    std::vector<std::vector<float>> planes;
    for (const PassImage& img : frame.passes) {
        const PassInfo& info = pass_info(img.pass);
        for (int c = 0; c < img.channels; ++c) {
            std::vector<float> plane(std::size_t(w) * std::size_t(h));
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    plane[std::size_t(y) * w + x] =
                        img.pixels[(std::size_t(h - 1 - y) * w + x) * img.channels + c];
            planes.push_back(std::move(plane));
            const std::string name = std::string("ViewLayer.") + info.name + "." + info.chan_id[c];
            header.channels().insert(name, Imf::Channel(Imf::FLOAT));
            fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes.back().data()), sizeof(float),
                                       sizeof(float) * std::size_t(w)));
        }
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
}

static unsigned char to_srgb8(float v) {
    v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
    const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    return static_cast<unsigned char>(std::lround(s * 255.0f));
}

void write_png_preview(const std::string& path, const PassImage& img) {
    const int w = img.width, h = img.height;
    std::vector<unsigned char> rgba(std::size_t(w) * h * 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* p = &img.pixels[(std::size_t(h - 1 - y) * w + x) * img.channels];
            unsigned char* q = &rgba[(std::size_t(y) * w + x) * 4];
            for (int c = 0; c < 3; ++c) q[c] = to_srgb8(p[std::min(c, img.channels - 1)]);
            q[3] = img.channels == 4 ? static_cast<unsigned char>(std::lround(std::clamp(p[3], 0.0f, 1.0f) * 255)) : 255;
        }
    std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
    if (!f) throw Error("cannot open " + path + " for writing");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        throw Error("writing PNG " + path + " failed");
    }
    png_init_io(png, f.get());
    png_set_IHDR(png, info, png_uint_32(w), png_uint_32(h), 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < h; ++y) png_write_row(png, &rgba[std::size_t(y) * w * 4]);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
}

}  // namespace deferred::tools
