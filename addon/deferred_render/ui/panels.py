"""The engine's own panels, named DEFERRED_RENDER_PT_<name>.

They show only what Blender has no suitable panel for when this engine is
active: the add-on settings (samples, device), Film > Transparent, the pass
checkboxes the renderer honours, the light settings it reads (incl. Cast
Shadow), the material's Blend Mode and pass index.
"""

import bpy

from .. import native
from ..engine import passes as pass_table

ENGINE = "DEFERRED_RENDER"


class _EnginePanel:
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def split_layout(self):
        """The panel's layout with labels on the left, as Blender's own panels."""
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        return layout


class DEFERRED_RENDER_PT_sampling(_EnginePanel, bpy.types.Panel):
    bl_label = "Sampling"
    bl_context = "render"

    def draw(self, context):
        layout = self.split_layout()
        settings = context.scene.deferred_render
        col = layout.column(align=True)
        col.prop(settings, "viewport_samples", text="Viewport")
        col.prop(settings, "samples", text="Render")
        layout.prop(settings, "emission_samples")
        layout.prop(settings, "filter_splat")


class DEFERRED_RENDER_PT_lights(_EnginePanel, bpy.types.Panel):
    bl_label = "Lights"
    bl_context = "render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = self.split_layout()
        settings = context.scene.deferred_render
        layout.prop(settings, "light_culling")
        row = layout.row()
        row.active = settings.light_culling
        row.prop(settings, "light_threshold")
        layout.prop(settings, "light_samples")
        layout.prop(settings, "shadow_method")
        col = layout.column()
        col.active = settings.shadow_method == "MAPS"
        col.prop(settings, "shadow_quality")
        col.prop(settings, "shadow_resolution")


class DEFERRED_RENDER_PT_film(_EnginePanel, bpy.types.Panel):
    bl_label = "Film"
    bl_context = "render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = self.split_layout()
        layout.prop(context.scene.render, "film_transparent", text="Transparent")


class DEFERRED_RENDER_PT_device(_EnginePanel, bpy.types.Panel):
    bl_label = "Device"
    bl_context = "render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = self.split_layout()
        layout.prop(context.scene.deferred_render, "device_index")
        layout.prop(context.scene.deferred_render, "visibility_buffer")
        # Cycles' option, same meaning: keep the renderer (GL context,
        # programs, images) between renders and animation frames.
        layout.prop(context.scene.render, "use_persistent_data", text="Persistent Data")
        error = native.error_message()
        if error:
            col = layout.column(align=True)
            col.alert = True
            col.label(text="Native renderer not available:", icon='ERROR')
            for line in _wrap(error, 60):
                col.label(text=line)


def _wrap(text, width):
    words, line, lines = text.split(), "", []
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    if line:
        lines.append(line)
    return lines


_PASS_LABELS = {
    "use_pass_z": "Z",
    "use_pass_mist": "Mist",
    "use_pass_position": "Position",
    "use_pass_normal": "Normal",
    "use_pass_vector": "Vector",
    "use_pass_uv": "UV",
    "use_pass_object_index": "Object Index",
    "use_pass_material_index": "Material Index",
    "use_pass_diffuse_direct": "Diffuse Direct",
    "use_pass_diffuse_color": "Diffuse Color",
    "use_pass_glossy_direct": "Glossy Direct",
    "use_pass_glossy_color": "Glossy Color",
    "use_pass_emit": "Emission",
    "use_pass_environment": "Environment",
    "use_pass_shadow": "Shadow",
    "use_pass_ambient_occlusion": "Ambient Occlusion",
    "cycles.use_pass_shadow_catcher": "Shadow Catcher",
}


class DEFERRED_RENDER_PT_passes(_EnginePanel, bpy.types.Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        layout = self.split_layout()
        view_layer = context.view_layer
        mod = native.try_load()
        if mod is None:
            layout.label(text="Native renderer not available (see Render > Device)", icon='ERROR')
            return
        col = layout.column(heading="Include", align=True)
        # Combined is always produced (Blender's image output needs it).
        for flag in pass_table.supported_flags(mod.PASSES):
            owner, name = pass_table.flag_owner(view_layer, flag)
            if owner is not None:
                col.prop(owner, name, text=_PASS_LABELS.get(flag, flag))
        col = layout.column(heading="Cryptomatte", align=True)
        col.prop(view_layer, "use_pass_cryptomatte_object", text="Object")
        col.prop(view_layer, "use_pass_cryptomatte_material", text="Material")
        col.prop(view_layer, "use_pass_cryptomatte_asset", text="Asset")
        layout.prop(view_layer, "pass_cryptomatte_depth", text="Levels")
        # Shader AOVs and light groups: Blender's own lists and operators.
        layout.label(text="Shader AOV")
        row = layout.row()
        row.template_list("VIEWLAYER_UL_aov", "aovs", view_layer, "aovs", view_layer, "active_aov_index", rows=2)
        col = row.column(align=True)
        col.operator("scene.view_layer_add_aov", icon='ADD', text="")
        col.operator("scene.view_layer_remove_aov", icon='REMOVE', text="")
        layout.label(text="Light Groups")
        row = layout.row()
        row.template_list("UI_UL_list", "lightgroups", view_layer, "lightgroups", view_layer,
                          "active_lightgroup_index", rows=2)
        col = row.column(align=True)
        col.operator("scene.view_layer_add_lightgroup", icon='ADD', text="")
        col.operator("scene.view_layer_remove_lightgroup", icon='REMOVE', text="")


class DEFERRED_RENDER_PT_light(_EnginePanel, bpy.types.Panel):
    bl_label = "Light"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return context.light is not None and context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        light = context.light
        layout.row().prop(light, "type", expand=True)
        layout.use_property_split = True
        col = layout.column()
        col.prop(light, "color")
        col.prop(light, "energy")
        col.separator()
        if light.type in {'POINT', 'SPOT'}:
            col.prop(light, "shadow_soft_size", text="Radius")
        elif light.type == 'SUN':
            col.prop(light, "angle")
        elif light.type == 'AREA':
            col.prop(light, "shape")
            sub = col.column(align=True)
            if light.shape in {'SQUARE', 'DISK'}:
                sub.prop(light, "size")
            else:
                sub.prop(light, "size", text="Size X")
                sub.prop(light, "size_y", text="Y")
        col.separator()
        col.prop(light, "use_shadow", text="Cast Shadow")


# What each Blend Mode does in this engine (README: Transparency).
BLEND_MODE_HELP = {
    'OPAQUE': ("Alpha as Cycles renders it: stochastic,", "converging over the samples"),
    'HASHED': ("Alpha as Cycles renders it: stochastic,", "converging over the samples"),
    'CLIP': ("Opaque where alpha is above the threshold,", "absent elsewhere (EEVEE's clip)"),
    'BLEND': ("Forward pass: blended over what is behind,", "exact at one sample; layers sorted per object"),
}


class DEFERRED_RENDER_PT_material_settings(_EnginePanel, bpy.types.Panel):
    bl_label = "Settings"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        mat = context.material
        return mat is not None and not mat.grease_pencil and context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.split_layout()
        mat = context.material
        layout.prop(mat, "blend_method", text="Blend Mode")
        if mat.blend_method == 'CLIP':
            layout.prop(mat, "alpha_threshold", text="Clip Threshold")
        col = layout.column(align=True)
        col.scale_y = 0.8
        for line in BLEND_MODE_HELP[mat.blend_method]:
            col.label(text=line)
        layout.prop(mat, "pass_index")


class _LightGroupPanel(_EnginePanel):
    """The Light Group field of the tab's datablock (object or world)."""
    bl_label = "Light Group"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return cls.datablock(context) is not None and context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        self.split_layout().prop_search(self.datablock(context), "lightgroup", context.view_layer, "lightgroups",
                                        text="Light Group")


class DEFERRED_RENDER_PT_object_light_group(_LightGroupPanel, bpy.types.Panel):
    bl_context = "object"

    @staticmethod
    def datablock(context):
        return context.object


class DEFERRED_RENDER_PT_world_light_group(_LightGroupPanel, bpy.types.Panel):
    bl_context = "world"

    @staticmethod
    def datablock(context):
        return context.world


class DEFERRED_RENDER_PT_world_preview(_EnginePanel, bpy.types.Panel):
    """The world's preview, rendered by this engine (Blender's own World
    tab has none for engines other than Cycles; materials and lights use
    Blender's preview panels)."""
    bl_label = "Preview"
    bl_context = "world"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return context.world is not None and context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        self.layout.template_preview(context.world)


class DEFERRED_RENDER_PT_viewport_render_pass(bpy.types.Panel):
    """Render Pass in the 3D view's shading popover, as Cycles and EEVEE have it."""
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'HEADER'
    bl_label = "Render Pass"
    bl_parent_id = 'VIEW3D_PT_shading'
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        view = context.space_data
        return (context.engine in cls.COMPAT_ENGINES and view is not None
                and getattr(view, "shading", None) is not None and view.shading.type == 'RENDERED')

    def draw(self, context):
        self.layout.prop(context.space_data.shading.deferred_render, "render_pass", text="")


classes = (
    DEFERRED_RENDER_PT_viewport_render_pass,
    DEFERRED_RENDER_PT_sampling,
    DEFERRED_RENDER_PT_lights,
    DEFERRED_RENDER_PT_film,
    DEFERRED_RENDER_PT_device,
    DEFERRED_RENDER_PT_passes,
    DEFERRED_RENDER_PT_light,
    DEFERRED_RENDER_PT_material_settings,
    DEFERRED_RENDER_PT_object_light_group,
    DEFERRED_RENDER_PT_world_light_group,
    DEFERRED_RENDER_PT_world_preview,
)
