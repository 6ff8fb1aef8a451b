"""Settings of the engine: one PointerProperty group, ``scene.deferred_render``.

Only what the renderer adds is here. Everything Blender already has a setting
for (resolution and percentage, border/crop, film transparent, frame range,
view layers and their pass checkboxes, mist, pass indices, light use_shadow,
render visibility) is read from Blender's own properties, not duplicated.
"""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty


def _redraw_views(self, context):
    """A setting the viewport reads in view_draw: redraw the 3D views (a
    property of ours tags nothing by itself)."""
    screen = getattr(context, "screen", None)
    for area in (screen.areas if screen is not None else ()):
        if area.type == 'VIEW_3D':
            area.tag_redraw()


class DeferredRenderSettings(bpy.types.PropertyGroup):
    samples: IntProperty(
        name="Samples",
        description="Number of jittered samples accumulated per pixel (anti-aliasing and soft shadows)",
        default=16,
        min=1,
        soft_max=256,
        max=4096,
    )
    emission_samples: IntProperty(
        name="Emission Samples",
        description=(
            "Camera samples of directly seen emission per sample: small bright emitters in view "
            "(fairy lights, bulbs) converge as with this many times the samples, for one more "
            "geometry pass each (no lighting). Used where an emissive mesh is in view, without "
            "Blend-mode materials or light groups. 0: automatic (4 where an emissive mesh in view "
            "is brighter than 8, radiance); 1: none"
        ),
        default=0,
        min=0,
        soft_max=16,
        max=64,
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
        update=_redraw_views,
    )
    filter_splat: BoolProperty(
        name="Filter Splatting",
        description=(
            "Each pixel also takes its neighbours' samples, weighted by the pixel filter: the same "
            "converged image, with much less noise where the filter's edge reaches a small, very "
            "bright feature (a highlight). Neighbouring pixels' noise becomes correlated, which "
            "denoisers handle less well. Off: each pixel its own samples only, as Cycles"
        ),
        default=True,
        update=_redraw_views,
    )
    visibility_buffer: BoolProperty(
        name="Visibility Buffer",
        description=(
            "The raster pipeline only finds which triangle each pixel sees; materials are evaluated "
            "and the G-buffer written by compute shaders, which data-centre GPUs run far faster "
            "than fragment shading. The same image"
        ),
        default=True,
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
    light_samples: IntProperty(
        name="Light Samples",
        description=(
            "Lights shaded per pixel and sample where more lights reach a pixel: each is picked "
            "with a probability from its share of the light there and weighted by its inverse, so "
            "the image converges to every light's sum as samples accumulate (suns and emissive "
            "meshes are always shaded). 0: every light every sample (exact per sample, slow with "
            "many lights). With Shadow Rays the lights come in groups of 8, so only values below 8 "
            "select there"
        ),
        default=16,
        min=0,
        soft_max=64,
        max=511,
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
    shadow_method: EnumProperty(
        name="Shadows",
        description="How each sample's visibility of a light and of the world is found",
        items=(
            ("MAPS", "Shadow Maps",
             "Rasterised depth maps from each sample's light point (fast; converges to the map's "
             "resolution, Shadow Quality)"),
            ("RAYS", "Shadow Rays",
             "Rays traced against the scene's triangles from each pixel (converges to Cycles' shadows; "
             "a node material that drives alpha makes the render fall back to maps, with a warning)"),
        ),
        default="MAPS",
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


# The passes the Rendered viewport can show (its Render Pass menu): the
# renderer's passes that accumulate while it samples (DiffDir, GlossDir and
# Shadow are resolved only after the last sample).
VIEWPORT_PASSES = (
    ("Combined", "Combined", "The lit image"),
    ("Emit", "Emission", "Emitted light"),
    ("Env", "Environment", "The world where it is seen"),
    ("AO", "Ambient Occlusion", "Ambient occlusion"),
    ("DiffCol", "Diffuse Color", "Diffuse albedo"),
    ("GlossCol", "Glossy Color", "Glossy albedo"),
    ("Normal", "Normal", "World-space shading normal"),
    ("Position", "Position", "World-space position"),
    ("UV", "UV", "The active UV map"),
    ("Depth", "Depth", "Distance along the view axis"),
    ("Mist", "Mist", "Mist factor"),
)


class DeferredViewportShading(bpy.types.PropertyGroup):
    """The 3D view's settings for this engine (``View3DShading.deferred_render``)."""
    render_pass: EnumProperty(
        name="Render Pass",
        description="The pass the Rendered viewport shows",
        items=VIEWPORT_PASSES,
        default="Combined",
        update=_redraw_views,
    )


classes = (DeferredRenderSettings, DeferredViewportShading)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.deferred_render = PointerProperty(
        type=DeferredRenderSettings, name="Deferred Render Settings"
    )
    bpy.types.View3DShading.deferred_render = PointerProperty(
        type=DeferredViewportShading, name="Deferred Viewport Settings"
    )


def unregister():
    del bpy.types.View3DShading.deferred_render
    del bpy.types.Scene.deferred_render
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
