#!/usr/bin/python3.11
"""Writes a PNG preview of a multilayer EXR's Combined pass (Standard view
transform: linear -> sRGB, clamped). Usage: exr_to_png.py IN.exr OUT.png"""
import sys

import numpy as np
import OpenImageIO as oiio


def main(src, dst):
    inp = oiio.ImageInput.open(src)
    if inp is None:
        sys.exit(f"cannot open {src}: {oiio.geterror()}")
    spec = inp.spec()
    names = list(spec.channelnames)
    pixels = inp.read_image(0, spec.nchannels, "float")
    inp.close()
    wanted = []
    for c in "RGBA":
        match = [i for i, n in enumerate(names) if n.endswith(f"Combined.{c}") or n == c]
        if not match:
            sys.exit(f"{src} has no Combined.{c} channel (channels: {names})")
        wanted.append(match[0])
    rgba = np.nan_to_num(pixels[:, :, wanted]).clip(0.0, 1.0)
    rgb = rgba[:, :, :3]
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1 / 2.4) - 0.055)
    out8 = (np.concatenate([srgb, rgba[:, :, 3:]], axis=2) * 255 + 0.5).astype(np.uint8)
    buf = oiio.ImageBuf(oiio.ImageSpec(spec.width, spec.height, 4, "uint8"))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(out8))
    if not buf.write(dst):
        sys.exit(f"writing {dst} failed: {buf.geterror()}")
    print(f"wrote {dst}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
