"""Settings of the engine: one PointerProperty group, ``scene.deferred_render``.

Only what the renderer adds is here. Everything Blender already has a setting
for (resolution and percentage, border/crop, film transparent, frame range,
view layers and their pass checkboxes, mist, pass indices, light use_shadow,
render visibility) is read from Blender's own properties, not duplicated.
"""

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, PointerProperty


class DeferredRenderSettings(bpy.types.PropertyGroup):
    samples: IntProperty(
        name="Samples",
        description="Number of jittered samples accumulated per pixel (anti-aliasing and soft shadows)",
        default=16,
        min=1,
        soft_max=256,
        max=4096,
    )
    viewport_samples: IntProperty(
        name="Viewport Samples",
        description=(
            "Samples the Rendered viewport accumulates; then it stops and the GPU idles until "
            "something changes"
        ),
        default=32,
        min=1,
        soft_max=256,
        max=4096,
    )
    light_culling: BoolProperty(
        name="Light Culling",
        description=(
            "Give each screen tile only the lights that can reach it (tiled culling). Off: "
            "every pixel evaluates every light (exact, slow with many lights)"
        ),
        default=True,
    )
    light_threshold: FloatProperty(
        name="Light Threshold",
        description=(
            "A light is cut off where it would make a white diffuse surface reflect less than "
            "this (scene-linear radiance at exposure 0; scaled by the view's exposure)"
        ),
        default=1e-3,
        min=0.0,
        soft_max=0.1,
        precision=5,
    )
    shadow_resolution: IntProperty(
        name="Max Shadow Resolution",
        description=(
            "Most texels per side of a shadow cube face / sun cascade (lights with Cast Shadow "
            "on); each light gets what its footprint on screen needs (Shadow Quality), up to "
            "this, lowered automatically to fit the memory budget"
        ),
        default=1024,
        min=64,
        max=8192,
    )
    shadow_quality: FloatProperty(
        name="Shadow Quality",
        description=(
            "Shadow map texels per pixel of the visible surfaces a light reaches (90th "
            "percentile); each light's maps are sized from this, up to Max Shadow Resolution"
        ),
        default=1.0,
        min=0.05,
        max=16.0,
        soft_max=4.0,
    )
    device_index: IntProperty(
        name="Device",
        description=(
            "GPU used for rendering; -1 picks automatically. With NVIDIA GPUs this indexes the "
            "GPUs CUDA_VISIBLE_DEVICES leaves visible, in CUDA's order (-1: the one CUDA calls 0, "
            "the GPU a cluster scheduler gave this process); otherwise it indexes EGL devices "
            "(-1: first hardware device, else Mesa surfaceless). DEFERRED_EGL_DEVICE overrides -1"
        ),
        default=-1,
        min=-1,
        max=64,
    )


classes = (DeferredRenderSettings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.deferred_render = PointerProperty(
        type=DeferredRenderSettings, name="Deferred Render Settings"
    )


def unregister():
    del bpy.types.Scene.deferred_render
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
