#include <deferred/scene.h>

namespace deferred {

Mat4d identity_matrix() {
    Mat4d m{};
    m[0] = m[5] = m[10] = m[15] = 1.0;
    return m;
}

}  // namespace deferred
