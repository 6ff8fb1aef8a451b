// A GL context on the test's own thread, for GPU unit tests that dispatch
// one shader of the library on a small buffer (EEVEE's GPU test style).
#pragma once

#include "egl_context.h"
#include "gl_util.h"
#include "shader_library.h"

#include <gtest/gtest.h>

#include <memory>

namespace deferred::testing {

class GLTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        context_ = std::make_unique<EglContext>(-1);
        shaders_ = std::make_unique<ShaderLibrary>();
    }
    static void TearDownTestSuite() {
        shaders_.reset();
        context_.reset();
    }
    static ShaderLibrary& shaders() { return *shaders_; }

private:
    static inline std::unique_ptr<EglContext> context_;
    static inline std::unique_ptr<ShaderLibrary> shaders_;
};

}  // namespace deferred::testing
