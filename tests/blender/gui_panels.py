"""The engine's panels drawn by Blender's real UI (not -b): under Xvfb, with
the engine active, the Properties editor is switched to each tab that has a
panel of ours (Render, View Layer, Material with every Blend Mode, Light,
Object, World) and the 3D view's shading popover is opened in Rendered
shading (Render Pass); the window is redrawn each time; every panel of ours must have drawn without an
exception (their draw methods are wrapped, re-registered, to record what
happened; the drawing itself is Blender's).

    xvfb-run -a blender --factory-startup --addons deferred_render \\
        --python tests/blender/gui_panels.py

Exit status 0 when every panel drew, 1 otherwise (printed per panel).
"""

import os
import sys
import traceback

import bpy

RESULTS = {}


def recording(original, name):
    def draw(self, context):
        try:
            original(self, context)
            RESULTS.setdefault(name, "drew")
        except Exception:
            RESULTS[name] = traceback.format_exc()
            raise
    return draw


def wrap_draws():
    from deferred_render.ui import panels
    for cls in panels.classes:
        # Re-registered around the change: Blender keeps the draw it found
        # at registration (replacing it on a registered class crashes).
        bpy.utils.unregister_class(cls)
        cls.draw = recording(cls.draw, cls.__name__)
        # Closed panels draw nothing: open them all for the test.
        cls.bl_options = set(getattr(cls, "bl_options", set())) - {'DEFAULT_CLOSED'}
        bpy.utils.register_class(cls)
    return [cls.__name__ for cls in panels.classes]


def properties_area():
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == 'PROPERTIES':
                return window, area
    # The default layout has one; make one from the largest area otherwise.
    window = bpy.context.window_manager.windows[0]
    area = max(window.screen.areas, key=lambda a: a.width * a.height)
    area.type = 'PROPERTIES'
    return window, area


def steps():
    """One UI state per step; between steps Blender's event loop redraws
    the tagged area (the timer returns, Blender draws, the timer runs again)."""
    names = wrap_draws()
    scene = bpy.context.scene
    scene.render.engine = 'DEFERRED_RENDER'
    cube = bpy.data.objects["Cube"]
    light = bpy.data.objects["Light"]
    window, area = properties_area()
    view_layer = bpy.context.view_layer

    def show(tab):
        area.spaces.active.context = tab
        area.tag_redraw()

    for tab in ('RENDER', 'VIEW_LAYER'):
        show(tab)
        yield
    view_layer.objects.active = cube
    material = cube.active_material
    for method in ('OPAQUE', 'CLIP', 'HASHED', 'BLEND'):
        material.blend_method = method
        show('MATERIAL')
        yield
    view_layer.objects.active = light
    show('DATA')
    yield
    show('OBJECT')
    yield
    show('WORLD')
    yield
    # The Render Pass sub-panel of the 3D view's shading popover (Rendered
    # shading): the popover opened as a user opens it.
    view = next(a for a in window.screen.areas if a.type == 'VIEW_3D')
    view.spaces.active.shading.type = 'RENDERED'
    header = next(r for r in view.regions if r.type == 'HEADER')
    with bpy.context.temp_override(window=window, area=view, region=header):
        bpy.ops.wm.call_panel(name="VIEW3D_PT_shading", keep_open=False)
    yield
    yield
    for name in names:
        print(f"  {name}: {RESULTS.get(name, 'never drawn')}")
    failed = [n for n in names if RESULTS.get(n) != "drew"]
    print(f"gui_panels: {len(names) - len(failed)} of {len(names)} panels drew" +
          (f"; FAILED: {', '.join(failed)}" if failed else ""))
    sys.stdout.flush()
    os._exit(1 if failed else 0)


_steps = None


def tick():
    global _steps
    try:
        if _steps is None:
            _steps = steps()
        next(_steps)
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        os._exit(1)
    return 0.3  # long enough for the event loop to redraw the area


# After the window is up: a timer runs once the UI has started.
bpy.app.timers.register(tick, first_interval=0.5)
