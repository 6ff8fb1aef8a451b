"""Blender depsgraph -> native scene, as numpy arrays end to end.

One module per data-block kind (mesh, material, light, camera, world) and
``instances`` for the depsgraph walk; ``export_scene`` is the only entry
point the engine uses. The exporter talks to any object with the native
``Renderer`` scene API, which is how tests check it without a GPU.
"""

from . import camera, light, material, mesh, motion, world  # noqa: F401
from . import cryptomatte as crypto_export
from .instances import ExportStats, MeshKeeper, SceneExporter  # noqa: F401


def requested_aovs(view_layer):
    """(name, 'COLOR' | 'VALUE') of the view layer's valid shader AOVs."""
    if view_layer is None:
        return []
    return [(a.name, a.type) for a in getattr(view_layer, "aovs", ()) if a.is_valid and a.name]


def light_group_indices(view_layer):
    """{light group name: its index from 1} of the view layer's light groups."""
    if view_layer is None:
        return {}
    return {g.name: k + 1 for k, g in enumerate(getattr(view_layer, "lightgroups", ())) if g.name}


def export_scene(depsgraph, renderer, warn=None, test_break=None, mesh_keeper=None, motion=None):
    """Clear ``renderer`` and sync the evaluated scene into it.

    Returns (stats, cancelled). ``warn(message)`` receives every warning
    once; ``test_break()`` is polled during the walk. ``mesh_keeper``
    (instances.MeshKeeper): meshes the renderer kept from the last sync are
    found again instead of exported (the viewport). ``motion``
    (motion.Motion): the neighbouring frames, for the Vector pass.
    """
    renderer.clear_scene()
    layers, _ = crypto_export.enabled_layers(getattr(depsgraph, "view_layer", None))
    view_layer = getattr(depsgraph, "view_layer", None)
    exporter = SceneExporter(renderer, warn=warn, test_break=test_break,
                             cryptomatte=crypto_export.Manifests(layers),
                             aovs_requested=bool(requested_aovs(view_layer)),
                             light_groups=light_group_indices(view_layer),
                             mesh_keeper=mesh_keeper, motion=motion)
    completed = exporter.sync(depsgraph)
    if completed:
        scene_world = depsgraph.scene.world
        camera = depsgraph.scene.camera
        orthographic = camera is not None and getattr(camera.data, "type", "") == "ORTHO"
        world.export_world(scene_world, renderer, exporter.image_registry, warn,
                           light_group=exporter.light_group_of(scene_world), orthographic=orthographic)
    exporter.stats.cryptomatte = exporter.cryptomatte
    return exporter.stats, not completed
