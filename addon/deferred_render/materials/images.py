"""Blender images as texel arrays for the Image and Environment Texture nodes,
holding what Cycles 3.4 holds in its image textures.

The node builder calls ``image_pixels(image)`` once per image per render,
uploads ``ImagePixels.pixels`` (uint8 -> GL_RGBA8, float32 -> GL_RGBA32F,
texel (x, y) = pixels[y, x], row 0 the bottom row) and binds it; the node spec
(materials/nodes/image.py) passes ``image_flags(...)`` to the GLSL
(shaders/nodes/node_image_lib.glsl), which filters with texelFetch exactly as
Cycles' CPU kernel does and then applies the flags. ``ImageUnavailable`` makes
the builder bind Cycles' missing-image magenta instead.

What Cycles stores, and so what is reproduced here. Sources: Cycles 3.4
intern/cycles/blender/shader.cpp (which images are "builtin"),
blender/image.cpp BlenderImageLoader, scene/image.cpp ImageManager
(file_load_image, image_associate_alpha, ImageMetaData::detect_colorspace),
scene/image_oiio.cpp OIIOImageLoader, scene/colorspace.cpp, util/half.h; the
places where the 3.4 behaviour differs from the sources' other versions were
settled by rendering with Blender 3.4.1's Cycles (see the report of this work):

- Packed, generated and movie images are "builtin": Cycles copies Blender's
  own buffers. Float buffers are copied as they are (Blender's scene-linear,
  associated alpha; no colour space step). Byte buffers are copied and, unless
  the alpha is data (Non-Color/Raw colour space, Channel Packed, None),
  premultiplied in integers: c * a / 255, truncated.
- Every other image is read from its file by OpenImageIO, unassociated, and
  Cycles associates 4-channel images itself (c * a / max in integers for 8 and
  16 bits; grey + alpha stays unassociated; EXR alpha is associated already).
  8-bit files: Blender's bytes are the file's bytes (for alpha mode
  Premultiplied Blender un-premultiplied them; they are rebuilt). 16-bit files
  (in Blender a decoded, premultiplied float buffer) are turned back into their
  16-bit values. Float files (EXR, HDR) are Blender's floats with Blender's
  alpha and colour steps undone; half-float EXRs go through Cycles' CPU
  half-to-float bit trick (a half zero reads as 2^-15: ``_half_bits_to_float_image``).
- sRGB images stay sRGB-encoded and are decoded after interpolation
  (NODE_IMAGE_COMPRESS_AS_SRGB: flag ``srgb``); Linear / Non-Color / Raw are
  used as stored. Other colour spaces go through OpenColorIO: Cycles 3.4 turns
  8- and 16-bit images into half floats, un-associates, converts, associates;
  for 8-bit images that is done here with Blender's own OCIO (a temporary EXR
  loaded in that colour space), for float images Blender's pixels already hold
  the conversion.
- Alpha mode None (IMAGE_ALPHA_IGNORE) sets alpha to 1 after loading. A
  one-channel file is a one-channel texture in Cycles: its alpha reads 1
  (flag ``ALPHA_ONE``).

Not reproduced (a warning says so where it applies): UDIM tiles other than
1001 (they read as missing), the frame of image sequences / movies (the buffer
Blender holds is used), images larger than 8192 pixels (scaled down),
non-finite float texels (zeroed; Cycles' check misses three in four, the rest
render NaN/inf), 16-bit images in OCIO colour spaces (Blender's float
conversion instead of Cycles' half-float one: within 1 half-float step).
Alpha association of 8/16-bit formats other than PNG is assumed to be the same
as PNG's.
"""

import collections
import os
import struct
import threading

import numpy as np

MAX_SIZE = 8192

# Flag bits of node_image_lib.glsl (IMG_FLAG_*).
FLAG_SRGB = 1
FLAG_UNASSOCIATE = 2
FLAG_UDIM_1001 = 4
FLAG_ALPHA_ONE = 8

# Colour spaces of Blender 3.4's OCIO config that Cycles handles without OCIO.
_DATA_SPACES = ("Non-Color", "Raw")          # OCIO isdata: alpha untouched
_LINEAR_SPACES = ("Linear",)                 # scene linear: used as stored
_SRGB_SPACES = ("sRGB",)                     # kept encoded, decoded after interpolation
# File formats whose float buffer in Blender comes from float data (OIIO reads
# them as float/half); every other format with a float buffer is 16-bit integer.
_FLOAT_FILE_FORMATS = ("OPEN_EXR", "OPEN_EXR_MULTILAYER", "HDR")


class ImageUnavailable(Exception):
    """The image has no pixels to upload; the message says why."""


class ImagePixels:
    """Texels for upload plus what the GLSL needs to know about them.

    pixels         (H, W, 4) C-contiguous, uint8 or float32, row 0 = bottom.
    warnings       list of str.
    srgb           texels are sRGB-encoded: decode after interpolation.
    premultiplied  the colour holds associated alpha.
    alpha_is_data  Cycles never divides the colour by alpha for this image.
    udim           a tiled image of which tile 1001 is uploaded.
    single_channel Cycles stores one channel: alpha reads as 1 (flag ALPHA_ONE).
    """

    __slots__ = ("pixels", "warnings", "srgb", "premultiplied", "alpha_is_data", "udim",
                 "single_channel")

    def __init__(self, pixels, warnings, srgb, premultiplied, alpha_is_data, udim,
                 single_channel=False):
        self.pixels = pixels
        self.warnings = warnings
        self.srgb = srgb
        self.premultiplied = premultiplied
        self.alpha_is_data = alpha_is_data
        self.udim = udim
        self.single_channel = single_channel

    def flags(self, alpha_linked):
        """The GLSL flag bits for a node whose Alpha output is (not) used."""
        return _flags(self.srgb, self.alpha_is_data, self.udim, self.single_channel,
                      alpha_linked)


def _flags(srgb, alpha_is_data, udim, single_channel, alpha_linked):
    f = FLAG_SRGB if srgb else 0
    if alpha_linked and not alpha_is_data:
        f |= FLAG_UNASSOCIATE
    if udim:
        f |= FLAG_UDIM_1001
    if single_channel:
        f |= FLAG_ALPHA_ONE
    return f


# --------------------------------------------------------------------------------------
# The plan: what Cycles does with this image, from its settings alone
# --------------------------------------------------------------------------------------

class _Plan:
    __slots__ = ("name", "builtin", "storage", "space", "colorspace", "srgb", "associate",
                 "ignore_alpha", "alpha_is_data", "alpha_mode", "file_channels",
                 "single_channel", "path", "udim", "warnings")


def _image_path(image):
    import bpy

    try:
        return bpy.path.abspath(image.filepath_raw or image.filepath, library=image.library)
    except Exception:
        return ""


def _read_head(path, n=1 << 16):
    try:
        with open(path, "rb") as f:
            return f.read(n)
    except OSError:
        return b""


def _exr_channel_types(path):
    """Pixel types (0 uint, 1 half, 2 float) of the first part's channels, or None."""
    data = _read_head(path)
    if data[:4] != b"\x76\x2f\x31\x01":
        return None
    pos = 8
    try:
        while pos < len(data):
            end = data.index(b"\0", pos)
            name = data[pos:end]
            pos = end + 1
            if not name:
                return None
            end = data.index(b"\0", pos)
            pos = end + 1
            size = struct.unpack("<i", data[pos:pos + 4])[0]
            pos += 4
            if name == b"channels":
                body = data[pos:pos + size]
                types, p = [], 0
                while p < len(body) and body[p] != 0:
                    p = body.index(b"\0", p) + 1
                    types.append(struct.unpack("<i", body[p:p + 4])[0])
                    p += 16
                return types
            pos += size
    except (ValueError, struct.error):
        return None
    return None


def _plan(image):
    p = _Plan()
    p.name = image.name
    p.warnings = []
    source = image.source
    if source == "VIEWER" or getattr(image, "type", "") in ("RENDER_RESULT", "COMPOSITING"):
        raise ImageUnavailable(
            "a Render Result / Viewer image, which Cycles cannot load either")

    p.builtin = bool(image.packed_file) or source in ("GENERATED", "MOVIE")
    p.path = "" if p.builtin else _image_path(image)
    # A UDIM image with one tile is a plain image in Cycles (ImageTextureNode::compile
    # encodes a single slot, no tile lookup); with more tiles svm_node_tex_image looks
    # the tile up and reads missing (magenta) outside the existing ones.
    numbers = [t.number for t in image.tiles] if source == "TILED" else []
    p.udim = len(numbers) > 1
    if p.udim:
        p.warnings.append(
            "UDIM image: only the first tile is used, at tile 1001; the "
            f"other tiles ({', '.join(str(n) for n in numbers[1:])}) render as missing "
            "(magenta)")
    if source == "SEQUENCE":
        p.warnings.append("image sequence: the frame Blender has loaded is used, not the "
                          "node's frame")
    elif source == "MOVIE":
        p.warnings.append("movie: the frame Blender has loaded is used, not the node's "
                          "frame")
    if getattr(image, "type", "") == "MULTILAYER":
        p.warnings.append("multilayer EXR: the pass Blender shows is used")

    cs = image.colorspace_settings.name
    p.colorspace = cs
    alpha_mode = image.alpha_mode
    p.alpha_mode = alpha_mode
    data_space = cs in _DATA_SPACES
    # image.cpp image_associate_alpha(); shader_nodes.cpp: the same test gates
    # NODE_IMAGE_ALPHA_UNASSOCIATE.
    p.alpha_is_data = data_space or alpha_mode in ("CHANNEL_PACKED", "NONE")
    p.associate = not p.alpha_is_data
    p.ignore_alpha = alpha_mode == "NONE"

    is_float = image.is_float
    if is_float:
        if p.builtin:
            p.storage = "float"
        elif image.file_format in _FLOAT_FILE_FORMATS:
            types = _exr_channel_types(p.path) if image.file_format != "HDR" else None
            p.storage = "half" if (types and all(t == 1 for t in types)) else "float"
        else:
            p.storage = "ushort"
    else:
        p.storage = "byte"

    # ColorSpaceManager::detect_known_colorspace / ImageMetaData::detect_colorspace.
    if data_space or cs in _LINEAR_SPACES:
        p.space = "raw"
    elif cs in _SRGB_SPACES:
        p.space = "srgb"
    else:
        p.space = "ocio"
    if p.builtin and is_float:
        # BlenderImageLoader: float buffers are already converted by Blender.
        p.space = "raw" if p.space != "ocio" else "ocio-done"
    if p.space == "ocio":
        # 8-bit: Cycles converts the texels to scene linear with OCIO into half
        # floats (_ocio_bytes). Float and 16-bit: Blender's pixels hold the same
        # OCIO conversion.
        p.space = "ocio-byte" if p.storage == "byte" else "ocio-done"
    p.srgb = p.space == "srgb"

    # Channels in the file (Blender's buffers are always RGBA): image.depth is the
    # ImBuf's bits per pixel, 8 per byte channel or 32 per float channel.
    bits = 32 if is_float else 8
    depth = int(getattr(image, "depth", 0) or 0)
    p.file_channels = depth // bits if depth and depth % bits == 0 else 4
    # Cycles stores a one-channel image as a one-channel texture (metadata.channels
    # == 1: FILE from OIIO's channel count, builtin from Blender's buffer).
    if p.builtin:
        p.single_channel = is_float and int(getattr(image, "channels", 4) or 4) == 1
    else:
        p.single_channel = p.file_channels == 1
    if not p.builtin and p.file_channels != 4:
        # OIIOImageLoader associates alpha only for 4-channel images
        # (oiio_load_pixels: components == 4); grey + alpha stays unassociated.
        p.associate = False
    if not p.builtin and p.storage in ("float", "half"):
        # OIIO reads EXR/HDR data as stored (EXR alpha is associated already).
        p.associate = False
    return p


def image_flags(image, alpha_linked):
    """Flag bits for node_tex_image / node_tex_environment (IMG_FLAG_*), from the
    image's settings only (cheap; no pixels are read). ``image`` None: the
    flags Cycles uses for a node without an image (raw colour space)."""
    if image is None:
        return _flags(False, False, False, False, alpha_linked)
    try:
        p = _plan(image)
    except ImageUnavailable:
        return _flags(False, False, False, False, alpha_linked)
    return _flags(p.srgb, p.alpha_is_data, p.udim, p.single_channel, alpha_linked)


# --------------------------------------------------------------------------------------
# Pixel conversions (numpy, vectorised)
# --------------------------------------------------------------------------------------

def _linear_to_srgb(c):
    """util/color.h color_linear_to_srgb (negative -> 0)."""
    c = np.asarray(c, np.float32)
    return np.where(c < 0.0031308, np.maximum(c, 0.0) * np.float32(12.92),
                    np.float32(1.055) * np.power(np.maximum(c, 0.0), np.float32(1.0 / 2.4))
                    - np.float32(0.055)).astype(np.float32)


def _to_rgba(a, channels):
    """(H, W, channels) -> (H, W, 4) as Cycles' file_load_image expands channels."""
    if channels == 4:
        return a
    h, w = a.shape[:2]
    out = np.empty((h, w, 4), a.dtype)
    one = 255 if a.dtype == np.uint8 else 1.0
    if channels == 1:
        out[..., 0:3] = a[..., 0:1]
        out[..., 3] = one
    elif channels == 2:
        out[..., 0:3] = a[..., 0:1]
        out[..., 3] = a[..., 1]
    else:
        out[..., 0:3] = a[..., 0:3]
        out[..., 3] = one
    return out


def _associate_uint(rgba, maxval):
    """In place: c = c * a / max in integers, truncated (Cycles: BlenderImageLoader's
    byte premultiply; OIIOImageLoader's util_image_multiply_native for uchar/ushort)."""
    alpha = rgba[..., 3]
    if alpha.min() == maxval:
        return rgba
    wide = np.uint32 if maxval == 65535 else np.uint16
    c = rgba[..., 0:3].astype(wide)
    c *= alpha[..., None].astype(wide)
    c //= wide(maxval)
    rgba[..., 0:3] = c
    return rgba


def _half_bits_to_float_image(f):
    """Cycles' CPU half_to_float_image() (util/half.h) applied to values that are
    half floats: x = (s << 16) | ((e + 0x1C000) << 13) | (m << 13) on the half bits,
    which maps +-0 to +-2^-15, denormals to 2^-15 * (1 + m / 1024) and inf/NaN to
    finite 65536-ish values, exactly as Cycles reads a half texture."""
    h = f.astype(np.float16).view(np.uint16).astype(np.uint32)
    x = ((h & 0x8000) << 16) | (((h & 0x7C00) + 0x1C000) << 13) | ((h & 0x03FF) << 13)
    return x.astype(np.uint32).view(np.float32)


def _half_texels(v):
    """_half_bits_to_float_image for float32 values known to be half floats (read
    from a half EXR), in place and cheaply: the bit trick equals the exact value
    for every normal half, so only zeros, denormals, inf and NaN change."""
    bits = v.view(np.uint32) & np.uint32(0x7FFFFFFF)
    # Normal halves: 2^-14 (0x38800000) .. 65504 (0x477FE000).
    special = (bits < np.uint32(0x38800000)) | (bits > np.uint32(0x477FE000))
    if special.any():
        idx = np.nonzero(special)
        v[idx] = _half_bits_to_float_image(v[idx])
    return v


def _float_to_half_image(f):
    """util/half.h float_to_half_image (CPU): truncating, flush to zero below 2^-14,
    clamped to 65504; returns the half bits' float value."""
    u = np.ascontiguousarray(f, np.float32).view(np.uint32)
    sign = (u & 0x80000000) >> 16
    exponent = u & 0x7F800000
    value = ((u & 0x7FFFFFFF) >> 13) - 0x1C000
    value = np.where(exponent < 0x38800000, 0, value)
    value = np.where(exponent > 0x47000000, 0x7BFF, value)
    value = np.where(exponent == 0, 0, value)
    bits = (value | sign).astype(np.uint16)
    return bits.view(np.float16).astype(np.float32)


def _zero_non_finite(rgba, warnings, name):
    bad = ~np.isfinite(rgba).all(axis=-1)
    n = int(np.count_nonzero(bad))
    if n:
        rgba[bad] = 0.0
        warnings.append(f"{n} texels with NaN/inf set to 0 (Cycles renders most of them "
                        "as NaN/inf)")
    return rgba


def _read_blender_pixels(image, w, h):
    n = len(image.pixels)
    if n == 0 or n % (w * h) != 0:
        raise ImageUnavailable("no pixel data")
    channels = n // (w * h)
    buf = np.empty(n, np.float32)
    image.pixels.foreach_get(buf)
    return buf.reshape(h, w, channels), channels


def _unit_to_uint(a, maxval, dtype):
    """Blender's k / 255 (or k / 65535) floats back to the integers k (round to nearest)."""
    a = np.clip(a, 0.0, 1.0, out=a)
    a *= np.float32(maxval)
    a += np.float32(0.5)
    return a.astype(dtype)


# --------------------------------------------------------------------------------------
# image_pixels
# --------------------------------------------------------------------------------------

def image_pixels(image):
    """ImagePixels holding what Cycles 3.4 stores for ``image`` (see the module
    docstring), or ImageUnavailable."""
    import bpy

    if image is None:
        raise ImageUnavailable("no image")
    p = _plan(image)
    warnings = list(p.warnings)

    w, h = image.size[0], image.size[1]
    if w <= 0 or h <= 0:
        where = f" ({p.path})" if p.path else ""
        raise ImageUnavailable(f"could not be loaded{where}")

    copy = None
    try:
        src = image
        if max(w, h) > MAX_SIZE:
            s = MAX_SIZE / float(max(w, h))
            nw, nh = max(1, min(MAX_SIZE, round(w * s))), max(1, min(MAX_SIZE, round(h * s)))
            copy = image.copy()
            copy.scale(nw, nh)
            warnings.append(f"scaled from {w}x{h} to {nw}x{nh}: images are limited to "
                            f"{MAX_SIZE} pixels on a side (Cycles uses the full size)")
            src, w, h = copy, nw, nh
        raw, channels = _read_blender_pixels(src, w, h)
    finally:
        if copy is not None:
            bpy.data.images.remove(copy)

    if p.storage == "byte":
        pixels = _byte_texels(p, raw, channels)
        if p.space == "ocio-byte":
            pixels = _ocio_bytes(p, pixels, warnings)
        premultiplied = p.associate
    elif p.storage == "ushort":
        pixels = _ushort_texels(p, raw, channels)
        premultiplied = p.associate
    else:
        pixels = _float_texels(p, raw, channels, warnings)
        premultiplied = not p.alpha_is_data
    return ImagePixels(np.ascontiguousarray(pixels), warnings, p.srgb, premultiplied,
                       p.alpha_is_data, p.udim, p.single_channel)


def _byte_texels(p, raw, channels):
    """8-bit: Blender's byte buffer (straight alpha; Blender un-premultiplied it
    for alpha mode Premultiplied) -> Cycles' uchar4 texels."""
    rgba = _to_rgba(_unit_to_uint(raw, 255, np.uint8), channels)
    if p.ignore_alpha:
        rgba[..., 3] = 255
        return rgba
    if p.alpha_mode == "PREMUL" and not p.alpha_is_data and not p.builtin:
        # The file holds associated colour, which Blender un-premultiplied
        # (round(255 c / a), clamped); Cycles reads the file's bytes. Rebuild them:
        # round(c * a / 255) (exact for valid premultiplied data, c <= a).
        a = rgba[..., 3:4].astype(np.uint16)
        rgba[..., 0:3] = ((rgba[..., 0:3].astype(np.uint16) * a + 127) // 255).astype(np.uint8)
    if p.associate and p.space != "ocio-byte":  # _ocio_bytes associates in half
        _associate_uint(rgba, 255)
    return rgba


def _byte_to_float(b):
    """util_image_cast_to_float<uchar>: value * (1 / 255)."""
    return b.astype(np.float32) * np.float32(1.0 / 255.0)


def _write_exr(path, rgba):
    """A minimal uncompressed scanline OpenEXR file of float32 RGBA; rgba is
    (H, W, 4) with row 0 the bottom row (Blender's order)."""
    h, w = rgba.shape[:2]

    def attr(name, typ, value):
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(value)) + value

    # Channels A, B, G, R (sorted by name): FLOAT (2), not pLinear, sampling 1 x 1.
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1)
                      for c in "ABGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) +
              attr("channels", "chlist", chlist) +
              attr("compression", "compression", b"\0") +
              attr("dataWindow", "box2i", box) +
              attr("displayWindow", "box2i", box) +
              attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    line_bytes = w * 4 * 4
    start = len(header) + 8 * h
    offsets = struct.pack("<%dQ" % h, *[start + y * (8 + line_bytes) for y in range(h)])
    with open(path, "wb") as f:
        f.write(header)
        f.write(offsets)
        for y in range(h):
            row = rgba[h - 1 - y].astype("<f4")  # EXR's first line is the top one
            f.write(struct.pack("<ii", y, line_bytes))
            f.write(np.ascontiguousarray(row[:, [3, 2, 1, 0]].T).tobytes())


def _ocio_to_scene_linear(values, colorspace):
    """OCIO conversion colorspace -> scene linear of float RGB values (N, 3), done
    by Blender itself: the values go through a temporary float EXR loaded in that
    colour space (colormanage_imbuf_make_linear, alpha untouched as channel-packed),
    the conversion Cycles' ColorSpaceManager::to_scene_linear applies."""
    import tempfile

    import bpy

    n = values.shape[0]
    width = min(n, 4096)
    height = (n + width - 1) // width
    buf = np.ones((height * width, 4), np.float32)
    buf[:n, 0:3] = values
    fd, path = tempfile.mkstemp(suffix=".exr", prefix="dr_ocio_", dir=bpy.app.tempdir or None)
    os.close(fd)
    img = None
    try:
        _write_exr(path, buf.reshape(height, width, 4))
        img = bpy.data.images.load(path, check_existing=False)
        img.alpha_mode = "CHANNEL_PACKED"
        img.colorspace_settings.name = colorspace
        if tuple(img.size) != (width, height) or not img.is_float:
            raise ImageUnavailable("the conversion image did not load")
        out = np.empty(width * height * 4, np.float32)
        img.pixels.foreach_get(out)
        return out.reshape(-1, 4)[:n, 0:3]
    finally:
        if img is not None:
            bpy.data.images.remove(img)
        try:
            os.remove(path)
        except OSError:
            pass


def _ocio_bytes(p, rgba, warnings):
    """8-bit image in a colour space Cycles converts with OCIO. Cycles 3.4
    (ImageMetaData::detect_colorspace) stores it as half floats: the bytes become
    halves (OIIO's uchar -> half rounding for files; BlenderImageLoader's
    float_to_half_image for builtin images), alpha is associated in half
    (util_image_multiply_native<half> / the loader's float product), then
    ColorSpaceManager::to_scene_linear<half>: un-associate, OCIO to scene linear,
    associate, float_to_half_image; the kernel reads them with half_to_float_image.
    ``rgba`` is Blender's straight uchar4 data (alpha already 255 for alpha mode
    None). Converted per distinct RGBA value."""
    flat = np.ascontiguousarray(rgba).reshape(-1, 4)
    keys = flat.view(np.uint32).ravel()
    uniq, inverse = np.unique(keys, return_inverse=True)
    texels = uniq.view(np.uint8).reshape(-1, 4)
    v = _byte_to_float(texels)
    if p.builtin:
        if p.associate:
            alpha = v[:, 3:4]
            h = np.concatenate([_float_to_half_image(v[:, 0:3] * alpha),
                                _float_to_half_image(alpha)], axis=1)
        else:
            h = _float_to_half_image(v)
    else:
        h = v.astype(np.float16).astype(np.float32)  # OIIO: round to nearest half
        if p.associate:
            hf = _half_bits_to_float_image(h)
            h[:, 0:3] = _float_to_half_image(hf[:, 0:3] * hf[:, 3:4])
    f = _half_bits_to_float_image(h)  # cast_to_float4 of half texels
    a = f[:, 3:4]
    assoc = ~((a <= 0.0) | (a == 1.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.float32(1.0) / np.where(assoc, a, 1.0)
    rgb = np.where(assoc, f[:, 0:3] * inv, f[:, 0:3]).astype(np.float32)
    try:
        lin = _ocio_to_scene_linear(rgb, p.colorspace)
    except Exception as ex:  # Blender could not do it: leave the values unconverted
        warnings.append(f"colour space '{p.colorspace}' could not be converted ({ex}); "
                        "its values are used as linear")
        lin = rgb
    lin = np.where(assoc, lin * a, lin)
    out = np.empty((texels.shape[0], 4), np.float32)
    out[:, 0:3] = _half_bits_to_float_image(_float_to_half_image(lin))
    out[:, 3:4] = f[:, 3:4]
    return out[inverse].reshape(rgba.shape)


def _file_values(p, rgba):
    """Float buffer of an image Cycles reads from its file (16-bit or float): undo
    what Blender did at load (imb_handle_alpha: premultiply straight data, keep
    premultiplied data; colormanage_imbuf_make_linear: decode with pre-division
    unless the alpha is data) and return the file's values, straight for
    STRAIGHT images, associated for PREMUL ones, as float32 in 0..1 (16-bit) or
    as stored (float)."""
    alpha = rgba[..., 3:4]
    c = rgba[..., 0:3]
    divided = not p.alpha_is_data
    if p.space == "raw" and (p.alpha_mode == "PREMUL" or not divided):
        return rgba  # Blender changed nothing
    if divided:
        with np.errstate(divide="ignore", invalid="ignore"):
            safe = np.where(alpha > 0.0, alpha, 1.0)
            c = np.where((alpha > 0.0) & (alpha != 1.0), c / safe, np.where(alpha > 0.0, c, 0.0))
    if p.space == "srgb":
        c = _linear_to_srgb(c)
    if p.alpha_mode == "PREMUL" and divided:
        c = np.where(alpha != 1.0, c * alpha, c)
    out = np.empty(rgba.shape, np.float32)
    out[..., 0:3] = c
    out[..., 3:4] = alpha
    return out


def _ushort_texels(p, raw, channels):
    """16-bit integer files: Blender's float buffer -> the file's 16-bit values ->
    Cycles' ushort4 texels (associated by OIIOImageLoader for 4-channel files),
    as float32 v * (1 / 65535) like Cycles' ushort read."""
    rgba = _to_rgba(raw, channels)
    if p.ignore_alpha:
        rgba[..., 3] = 1.0
    if p.space == "ocio-done":
        # Cycles converts through OCIO into half floats: Blender's converted floats,
        # rounded as float_to_half_image and read back as half_to_float_image.
        return _half_bits_to_float_image(_float_to_half_image(rgba))
    vals = _file_values(p, rgba)
    u16 = _unit_to_uint(np.array(vals, np.float32), 65535, np.uint16)
    if p.ignore_alpha:
        u16[..., 3] = 65535
    elif p.associate:
        _associate_uint(u16, 65535)
    return u16.astype(np.float32) * np.float32(1.0 / 65535.0)


def _float_texels(p, raw, channels, warnings):
    """Float buffers. Builtin: Blender's floats as they are (BlenderImageLoader).
    Files: the file's values (float, or half read through half_to_float_image)."""
    rgba = _to_rgba(raw, channels)
    if p.ignore_alpha:
        rgba[..., 3] = 1.0
    if p.builtin:
        return _zero_non_finite(rgba, warnings, p.name)
    if p.space == "ocio-done":
        if p.storage == "half":
            # to_scene_linear<half> wrote float_to_half_image() of the converted floats.
            return _half_bits_to_float_image(_float_to_half_image(rgba))
        return _zero_non_finite(rgba, warnings, p.name)
    vals = _file_values(p, rgba)
    if p.storage == "half":
        if vals is rgba:
            return _half_texels(rgba)  # unchanged file values: exact halves
        return _half_bits_to_float_image(vals)
    return _zero_non_finite(vals, warnings, p.name)


# --------------------------------------------------------------------------------------
# Across renders: every final render builds a new native renderer, but an
# animation or a re-render should not decode its images again. Keyed by what
# decides the texels; an image with unsaved edits (is_dirty) is never cached.
# --------------------------------------------------------------------------------------

CACHE_BYTES = 1 << 30
_cache = collections.OrderedDict()  # key -> ImagePixels, least recently used first
_cache_lock = threading.Lock()      # renders run on Blender's render thread, handlers on the main one


def _cache_key(image):
    import zlib

    if image is None or image.is_dirty:
        return None
    key = [image.name_full, image.source, image.colorspace_settings.name, image.alpha_mode,
           tuple(image.size), bool(image.use_half_precision) if hasattr(image, "use_half_precision") else None]
    if image.packed_file is not None:
        data = image.packed_file.data
        key += ["packed", len(data), zlib.crc32(data)]
    elif image.source == "GENERATED":
        key += ["generated", image.generated_type, image.generated_width, image.generated_height,
                tuple(image.generated_color), image.use_generated_float]
    elif image.source in {"FILE", "TILED"}:
        path = _image_path(image)
        try:
            key += ["file", path, os.path.getmtime(path), os.path.getsize(path)]
        except OSError:
            return None
    else:  # movies and sequences: the frame Blender holds changes
        return None
    return tuple(key)


def cached_image_pixels(image):
    """image_pixels(), remembered across renders (up to CACHE_BYTES of texels)."""
    key = _cache_key(image)
    if key is None:
        return image_pixels(image)
    with _cache_lock:
        hit = _cache.get(key)
        if hit is not None:
            _cache.move_to_end(key)
            return hit
    result = image_pixels(image)
    with _cache_lock:
        _cache[key] = result
        total = sum(r.pixels.nbytes for r in _cache.values())
        while total > CACHE_BYTES and len(_cache) > 1:
            _, old = _cache.popitem(last=False)
            total -= old.pixels.nbytes
    return result


def native_key(image):
    """A string naming the image's texels for the native image cache (a
    persistent renderer finds kept images by it), or "" when they have no
    stable name (unsaved edits, movies). The key holds everything that
    decides the texels (file, time and size, packed data, generation
    settings, colour space, alpha mode), so an edit that changes them gives a
    new key; unsaved pixel edits make the image dirty, hence keyless."""
    import hashlib
    key = _cache_key(image)
    if key is None:
        return ""
    return hashlib.sha1(repr(key).encode()).hexdigest()


def forget(name_full=None):
    """Drop the cached pixels of one image (by name_full), or of all. The
    pixels come from Blender's buffers, which a reload or an edit replaces
    without the file's time changing: the add-on calls this from its
    depsgraph and file-load handlers."""
    with _cache_lock:
        if name_full is None:
            _cache.clear()
        else:
            for key in [k for k in _cache if k[0] == name_full]:
                del _cache[key]
