"""Frame geometry: full render size, border region, and pass writing.

Resolution percentage: ``RenderEngine.resolution_x/y`` already hold the
scaled full-frame size (Blender's ``winx = size * xsch / 100``).

Border (Render Region): Blender's render result then covers only the border
rectangle ``disprect = border * winx`` (float product truncated to int, as in
``render_init_from_main``), and Blender itself crops or pads the final image
according to ``use_crop_to_border``, exactly as for Cycles. We render the
*full* frame and crop the border rectangle out of every pass: the projection
stays the camera's, pixels match a full render bit for bit, and the cost of
the unused area is the price (documented choice).
"""

import numpy as np


class FrameRect:
    """The part of the full frame [0, full_width) x [0, full_height) to
    write into the render result; y grows upwards (row 0 = bottom)."""

    __slots__ = ("full_width", "full_height", "x", "y", "width", "height")

    def __init__(self, full_width, full_height, x=0, y=0, width=None, height=None):
        self.full_width = int(full_width)
        self.full_height = int(full_height)
        self.x = int(x)
        self.y = int(y)
        self.width = self.full_width if width is None else int(width)
        self.height = self.full_height if height is None else int(height)

    @classmethod
    def from_render_settings(cls, render, full_width, full_height):
        if not render.use_border:
            return cls(full_width, full_height)
        # float32 arithmetic and truncation, as Blender's C code does it.
        f32 = np.float32
        xmin = int(f32(render.border_min_x) * f32(full_width))
        xmax = int(f32(render.border_max_x) * f32(full_width))
        ymin = int(f32(render.border_min_y) * f32(full_height))
        ymax = int(f32(render.border_max_y) * f32(full_height))
        xmin, xmax = max(0, min(xmin, full_width)), max(0, min(xmax, full_width))
        ymin, ymax = max(0, min(ymin, full_height)), max(0, min(ymax, full_height))
        return cls(full_width, full_height, xmin, ymin, xmax - xmin, ymax - ymin)

    def fit_to_result(self, result_width, result_height):
        """Trust Blender's result size if rounding disagreed by a pixel."""
        if (result_width, result_height) != (self.width, self.height):
            self.width = min(int(result_width), self.full_width - self.x)
            self.height = min(int(result_height), self.full_height - self.y)
        return self

    @property
    def is_full(self):
        return (self.x, self.y, self.width, self.height) == (0, 0, self.full_width, self.full_height)

    def crop(self, image):
        """Crop a (full_height, full_width, C) pass image to this rectangle."""
        if self.is_full:
            return image
        return image[self.y:self.y + self.height, self.x:self.x + self.width]

    def __repr__(self):
        return (f"FrameRect({self.full_width}x{self.full_height}, region {self.x},{self.y} "
                f"{self.width}x{self.height})")


def flatten_passes(render_passes, images, frame):
    """One float32 array with every pass of ``render_passes`` (a RenderLayer's
    ``passes``, in its order) for ``layer.passes.foreach_set("rect", ...)``.

    ``images`` maps pass name -> (full_height, full_width, C) array. A pass
    with no image is left at zero; a channel-count mismatch is padded with
    zeros or truncated (never expected from the native renderer). Returns
    (flat, missing pass names).
    """
    layout = [(p.name, int(p.channels)) for p in render_passes]
    pixels = frame.width * frame.height
    flat = np.zeros(sum(pixels * c for _, c in layout), dtype=np.float32)
    missing = []
    offset = 0
    for name, channels in layout:
        size = pixels * channels
        image = images.get(name)
        if image is None:
            missing.append(name)
        else:
            image = np.asarray(image)
            if image.ndim == 2:
                image = image[:, :, None]
            region = frame.crop(image)
            if region.shape[:2] != (frame.height, frame.width):
                raise ValueError(
                    f"pass {name}: renderer returned {image.shape[1]}x{image.shape[0]}, "
                    f"expected {frame.full_width}x{frame.full_height}")
            got = region.shape[2]
            dest = flat[offset:offset + size].reshape(frame.height, frame.width, channels)
            n = min(got, channels)
            dest[:, :, :n] = region[:, :, :n]
        offset += size
    return flat, missing
