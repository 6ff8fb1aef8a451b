"""The legacy texture mapping every Cycles texture node carries (set only by
old files and scripts in Blender 3.x): scene/shader_nodes.cpp
TextureMapping::skip() / compute_transform(). Shared by the texture and image
node specs; the GLSL side is tex_mapping_apply()."""

import math

MAP_NONE, MAP_AFFINE, MAP_AFFINE_NORMALIZE = 0, 1, 2

# --------------------------------------------------------------------------------------
# Texture mapping: scene/shader_nodes.cpp TextureMapping::skip() / compute_transform(),
# with util/transform.h's transform_scale/rotate/euler/translate (Transform = 3x4 rows).
# --------------------------------------------------------------------------------------

_AXIS = {"NONE": 0, "X": 1, "Y": 2, "Z": 3}   # TextureMapping::Mapping (= Blender's)


def _mul(a, b):
    """Product of two affine 3x4 transforms (rows), as Transform * Transform."""
    out = []
    for i in range(3):
        row = []
        for j in range(4):
            v = sum(a[i][k] * b[k][j] for k in range(3))
            if j == 3:
                v += a[i][3]
            row.append(v)
        out.append(row)
    return out


def _scale(s):
    return [[s[0], 0.0, 0.0, 0.0], [0.0, s[1], 0.0, 0.0], [0.0, 0.0, s[2], 0.0]]


def _translate(t):
    return [[1.0, 0.0, 0.0, t[0]], [0.0, 1.0, 0.0, t[1]], [0.0, 0.0, 1.0, t[2]]]


def _rotate(angle, axis):
    """util/transform.h transform_rotate() (axis is a unit axis here)."""
    s, c = math.sin(angle), math.cos(angle)
    t = 1.0 - c
    x, y, z = axis
    return [[x * x * t + c, x * y * t - s * z, x * z * t + s * y, 0.0],
            [y * x * t + s * z, y * y * t + c, y * z * t - s * x, 0.0],
            [z * x * t - s * y, z * y * t + s * x, z * z * t + c, 0.0]]


def _euler(r):
    """util/transform.h transform_euler(): Rz * Ry * Rx."""
    return _mul(_mul(_rotate(r[2], (0.0, 0.0, 1.0)), _rotate(r[1], (0.0, 1.0, 0.0))),
                _rotate(r[0], (1.0, 0.0, 0.0)))


def _inverse(m):
    """Inverse of an affine 3x4 transform (the 3x3 part by cofactors, then -A^-1 t).
    A singular matrix (Cycles nudges the diagonal, then gives up with the identity)
    gives the identity."""
    a = [row[:3] for row in m]
    t = [row[3] for row in m]
    c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1]
    c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2]
    c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0]
    det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02
    if det == 0.0 or not math.isfinite(det):
        return _scale((1.0, 1.0, 1.0))
    inv = [[c00 / det,
            (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / det,
            (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det],
           [c01 / det,
            (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / det,
            (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / det],
           [c02 / det,
            (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / det,
            (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / det]]
    return [inv[i] + [-sum(inv[i][k] * t[k] for k in range(3))] for i in range(3)]


def _signf(f):
    """util/math.h signf(): -1 for negative, else +1 (so +1 for -0.0 and 0.0)."""
    return -1.0 if f < 0.0 else 1.0


def compute_transform(translation, rotation, scale, vector_type, axes):
    """TextureMapping::compute_transform(): the 3x4 rows applied to the texture vector."""
    mmat = [[0.0] * 4 for _ in range(3)]
    for row, axis in enumerate(axes):
        index = _AXIS.get(axis, 0)
        if index != 0:
            mmat[row][index - 1] = 1.0

    scale_clamped = list(scale)
    if vector_type in ("TEXTURE", "NORMAL"):
        # keep matrix invertible
        scale_clamped = [_signf(v) * 1e-5 if abs(v) < 1e-5 else v for v in scale]

    smat = _scale(scale_clamped)
    rmat = _euler(rotation)
    tmat = _translate(translation)

    if vector_type == "TEXTURE":
        # inverse transform on texture coordinate gives forward transform on texture
        mat = _inverse(_mul(_mul(tmat, rmat), smat))
    elif vector_type == "POINT":
        mat = _mul(_mul(tmat, rmat), smat)
    elif vector_type == "VECTOR":
        mat = _mul(rmat, smat)
    else:  # NORMAL: no translation, inverse transpose (transform_transposed_inverse)
        inv = _inverse(_mul(rmat, smat))
        mat = [[inv[j][i] for j in range(3)] + [0.0] for i in range(3)]

    # projection last
    return _mul(mat, mmat)


def texture_mapping(mapping):
    """(mode, 12 floats or None) for a bpy TexMapping; MAP_NONE where Cycles skips it."""
    if mapping is None:
        return MAP_NONE, None
    t = tuple(float(v) for v in mapping.translation)
    r = tuple(float(v) for v in mapping.rotation)
    s = tuple(float(v) for v in mapping.scale)
    axes = (mapping.mapping_x, mapping.mapping_y, mapping.mapping_z)
    # TextureMapping::skip() (use_minmax is never set from Blender).
    if t == (0.0, 0.0, 0.0) and r == (0.0, 0.0, 0.0) and s == (1.0, 1.0, 1.0) and \
            axes == ("X", "Y", "Z"):
        return MAP_NONE, None
    vector_type = mapping.vector_type
    mat = compute_transform(t, r, s, vector_type, axes)
    block = [float(mat[i][j]) for i in range(3) for j in range(4)]
    return (MAP_AFFINE_NORMALIZE if vector_type == "NORMAL" else MAP_AFFINE), block


def mapping_args(b):
    """[mode, block offset] ints of tex_mapping_apply()."""
    mode, block = texture_mapping(getattr(b.node, "texture_mapping", None))
    if mode == MAP_NONE:
        return [b.int(MAP_NONE), b.int(0)]
    return [b.int(mode), b.block(block)]


