// Octahedral normal encoding as the G-buffer stores it (packUnorm2x16's
// bits in an R32UI target): measured angular error over >= 1e6 directions.
#include "gl_test_context.h"

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <cmath>
#include <random>
#include <vector>

using namespace deferred;

class NormalEncoding : public deferred::testing::GLTest {};

TEST_F(NormalEncoding, MaxAngularErrorBelowOneHundredthDegree) {
    const int width = 1024, n = width * 1024;
    std::vector<glm::vec4> dirs(n);
    std::mt19937 rng(42);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int i = 0; i < n; ++i) {
        glm::dvec3 d(g(rng), g(rng), g(rng));
        if (i < 6) d = glm::dvec3(0), d[i / 2] = (i % 2) ? -1 : 1;  // the axes, incl. -Z (octahedron fold)
        d = glm::normalize(d);
        dirs[i] = glm::vec4(glm::vec3(d), 0.0f);
    }
    Buffer in = make_storage_buffer(dirs.data(), dirs.size() * sizeof(glm::vec4), "dirs");
    Buffer out = make_storage_buffer(nullptr, dirs.size() * sizeof(glm::vec4), "decoded");
    Texture image = make_texture_2d(GL_R32UI, width, n / width, "encoded normals");
    glUseProgram(shaders().compute_program("unit_test_octahedral_comp.glsl", {}));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.get());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.get());
    glBindImageTexture(0, image.get(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
    glDispatchCompute(GLuint(n / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<glm::vec4> decoded(n);
    glGetNamedBufferSubData(out.get(), 0, GLsizeiptr(n * sizeof(glm::vec4)), decoded.data());
    check_gl("octahedral dispatch");
    double max_deg = 0, sum_deg = 0;
    for (int i = 0; i < n; ++i) {
        const glm::dvec3 a(dirs[i]), b(decoded[i]);
        // atan2 form: accurate for tiny angles, unlike acos.
        const double ang = std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) * 180.0 / M_PI;
        max_deg = std::max(max_deg, ang);
        sum_deg += ang;
    }
    std::printf("octahedral unorm16 x 2: mean %.5f deg, max %.5f deg over %d directions\n", sum_deg / n, max_deg, n);
    EXPECT_LT(max_deg, 0.01);
}
