"""Generate the sample scenes in blend_samples/.

    blender -b --factory-startup --python blend_samples/generate_samples.py [-- NAME ...]

writes blend_samples/{showcase,box_room,many_lights,instancing,analytic,materials,hdri_studio,sky_sun,
emitters}.blend
(all of them, or the NAMEs given after "--").

The files do not select the Deferred engine (the add-on need not be loaded
while generating); choose it on the command line:

    BLENDER_USER_SCRIPTS=$PWD/build/blender_scripts blender -b blend_samples/showcase.blend \
        --addons deferred_render -E DEFERRED_RENDER -o /tmp/out/frame_ -F OPEN_EXR_MULTILAYER -f 1

Every scene stores settings that make a comparison with Cycles fair (direct
light only: max_bounces 0, denoising off, Standard view transform) and with
EEVEE (light threshold 1e-4, soft shadows, no
GTAO/SSR/bloom; 1024 cube / 2048 cascade shadow maps, since 4096 crashes EEVEE
on llvmpipe), turns on every pass the Deferred engine produces, and writes
32-bit multilayer EXR by default.

The analytic scene is the reference for the pass tests: its geometry is
listed in ANALYTIC (also stored in the file as scene["analytic"]), so tests
can compute expected values without parsing meshes.
"""

import math
import os
import random
import sys

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))

# Passes the Deferred renderer produces (deferred_native.PASSES minus Combined).
PASS_FLAGS = (
    "use_pass_z", "use_pass_mist", "use_pass_position", "use_pass_normal", "use_pass_uv",
    "use_pass_object_index", "use_pass_material_index", "use_pass_diffuse_direct",
    "use_pass_diffuse_color", "use_pass_glossy_direct", "use_pass_glossy_color",
    "use_pass_emit", "use_pass_environment", "use_pass_shadow", "use_pass_ambient_occlusion",
)

# The analytic scene, in world units (metres). Spheres are smooth UV spheres
# (64 segments, 32 rings), planes are single quads.
ANALYTIC = {
    "camera": {"location": (0.0, -14.0, 5.0), "target": (0.0, 0.0, 1.0), "lens": 50.0},
    "camera_ortho": {"location": (0.0, -14.0, 5.0), "target": (0.0, 0.0, 1.0), "ortho_scale": 14.0},
    "floor": {"center": (0.0, 0.0, 0.0), "size": (16.0, 16.0), "normal": (0.0, 0.0, 1.0),
              "pass_index": 1, "material_pass_index": 11},
    "wall": {"center": (0.0, 6.0, 2.5), "size": (10.0, 5.0), "normal": (0.0, -1.0, 0.0),
             "pass_index": 2, "material_pass_index": 12},
    "spheres": [
        {"name": "SphereA", "center": (-3.5, 0.0, 1.0), "radius": 1.0, "pass_index": 3, "material_pass_index": 13},
        {"name": "SphereB", "center": (0.0, 0.5, 1.5), "radius": 1.5, "pass_index": 4, "material_pass_index": 14},
        {"name": "SphereC", "center": (3.5, -1.0, 1.0), "radius": 1.0, "pass_index": 5, "material_pass_index": 15},
    ],
    # A cube with two materials: top face uses slot 1.
    "box": {"name": "Box", "center": (-1.5, -4.0, 0.5), "size": 1.0, "pass_index": 6,
            "material_pass_index": (16, 17)},
}


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------

def new_scene(name, resolution=(640, 360)):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = name
    render = scene.render
    render.resolution_x, render.resolution_y = resolution
    render.resolution_percentage = 100
    render.film_transparent = False
    render.use_border = False
    scene.frame_start = scene.frame_end = scene.frame_current = 1
    img = render.image_settings
    img.file_format = 'OPEN_EXR_MULTILAYER'
    img.color_depth = '32'
    img.exr_codec = 'ZIP'
    render.use_compositing = True
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'

    # Cycles: direct light only, no denoiser (Debian's build has no OIDN).
    if hasattr(scene, "cycles"):
        cy = scene.cycles
        cy.device = 'CPU'
        cy.samples = 64
        cy.use_adaptive_sampling = False
        cy.use_denoising = False
        cy.max_bounces = 0
        cy.diffuse_bounces = cy.glossy_bounces = cy.transmission_bounces = 0
        cy.volume_bounces = cy.transparent_max_bounces = 0
        cy.caustics_reflective = cy.caustics_refractive = False
    # EEVEE: the fair-comparison settings of shared/REFERENCE.md.
    ee = scene.eevee
    ee.light_threshold = 1e-4
    ee.use_soft_shadows = True
    # REFERENCE.md suggests 4096 maps; EEVEE 3.4 on llvmpipe segfaults with
    # 4096 cube maps and more than a few lights, so 1024/2048 here.
    ee.shadow_cube_size = '1024'
    ee.shadow_cascade_size = '2048'
    ee.use_shadow_high_bitdepth = True
    ee.use_gtao = False
    ee.use_ssr = False
    ee.use_bloom = False
    ee.taa_render_samples = 16

    layer = scene.view_layers[0]
    layer.name = "ViewLayer"
    layer.use_pass_combined = True
    for flag in PASS_FLAGS:
        setattr(layer, flag, True)
    return scene


def set_world(scene, color=(0.05, 0.05, 0.05), strength=1.0):
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    world.color = color
    world.mist_settings.start = 5.0
    world.mist_settings.depth = 25.0
    world.mist_settings.falloff = 'QUADRATIC'
    scene.world = world
    return world


def principled(name, color=(0.8, 0.8, 0.8), metallic=0.0, roughness=0.5, specular=0.5,
               emission=None, emission_strength=1.0, pass_index=0, inputs=None):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Specular"].default_value = specular
    for key, value in (inputs or {}).items():
        bsdf.inputs[key].default_value = value
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission_strength
    mat.diffuse_color = (*color, 1.0)
    mat.metallic = metallic
    mat.roughness = roughness
    mat.pass_index = pass_index
    return mat


def shader_material(name, build, viewport=(0.8, 0.8, 0.8)):
    """A material whose surface is built by build(nodes, links) -> shader output socket."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.remove(nodes["Principled BSDF"])
    out = nodes["Material Output"]
    links.new(build(nodes, links), out.inputs["Surface"])
    mat.diffuse_color = (*viewport, 1.0)
    return mat


def link(obj, collection=None):
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def mesh_object(name, mesh, location=(0, 0, 0), material=None, pass_index=0, collection=None):
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    obj.pass_index = pass_index
    if material is not None:
        obj.data.materials.append(material)
    return link(obj, collection)


def primitive(op, name, material=None, pass_index=0, smooth=False, **kwargs):
    """Create a primitive with bpy.ops (needs a view layer) and return it."""
    op(**kwargs)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.name = name
    obj.pass_index = pass_index
    if material is not None:
        obj.data.materials.append(material)
    if smooth:
        for poly in obj.data.polygons:
            poly.use_smooth = True
    return obj


def plane_mesh(name, size_x, size_y):
    hx, hy = size_x / 2.0, size_y / 2.0
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(-hx, -hy, 0), (hx, -hy, 0), (hx, hy, 0), (-hx, hy, 0)], [], [(0, 1, 2, 3)])
    mesh.uv_layers.new(name="UVMap")
    uv = mesh.uv_layers[0].data
    for i, co in enumerate(((0, 0), (1, 0), (1, 1), (0, 1))):
        uv[i].uv = co
    mesh.update()
    return mesh


def look_at(obj, target):
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def add_camera(scene, name="Camera", location=(0, -10, 4), target=(0, 0, 1), lens=50.0,
               ortho_scale=None, active=True):
    cam = bpy.data.cameras.new(name)
    cam.lens = lens
    cam.sensor_width = 36.0
    cam.sensor_fit = 'AUTO'
    cam.clip_start = 0.1
    cam.clip_end = 200.0
    if ortho_scale is not None:
        cam.type = 'ORTHO'
        cam.ortho_scale = ortho_scale
    obj = link(bpy.data.objects.new(name, cam))
    obj.location = location
    look_at(obj, target)
    if active:
        scene.camera = obj
    return obj


def add_light(name, kind, location, energy, color=(1, 1, 1), target=None, collection=None, **props):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    for key, value in props.items():
        setattr(data, key, value)
    obj = link(bpy.data.objects.new(name, data), collection)
    obj.location = location
    if target is not None:
        look_at(obj, target)
    return obj


def save(scene, name):
    bpy.context.view_layer.update()
    path = os.path.join(HERE, f"{name}.blend")
    # Keep the files small and deterministic: no UI thumbnails, compressed.
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=True, check_existing=False)
    if os.path.exists(path + "1"):  # Blender's backup of the previous version
        os.remove(path + "1")
    print(f"generate_samples: wrote {path}")


# ---------------------------------------------------------------------------
# scenes
# ---------------------------------------------------------------------------

def build_showcase():
    scene = new_scene("Showcase")
    set_world(scene, (0.05, 0.05, 0.05))

    floor = mesh_object("Floor", plane_mesh("Floor", 30, 30),
                        material=principled("Floor", (0.6, 0.6, 0.6), roughness=0.7), pass_index=1)
    floor.location = (0, 0, 0)

    suzanne = primitive(bpy.ops.mesh.primitive_monkey_add, "Suzanne",
                        material=principled("Suzanne", (0.8, 0.25, 0.1), roughness=0.35, inputs={"Clearcoat": 0.5}),
                        pass_index=2, smooth=True, size=2.0, location=(-1.5, 0.5, 1.2))
    suzanne.rotation_euler = (math.radians(-10), 0, math.radians(15))
    mod = suzanne.modifiers.new("Subdivision", 'SUBSURF')
    mod.levels = mod.render_levels = 2

    primitive(bpy.ops.mesh.primitive_cube_add, "Cube",
              material=principled("Cube", (0.1, 0.3, 0.8), roughness=0.2), pass_index=3,
              size=1.2, location=(-4.6, 1.5, 0.6))
    # Diffuse + Glossy through a Mix Shader.
    def mix_build(nodes, links):
        diff = nodes.new("ShaderNodeBsdfDiffuse")
        diff.inputs["Color"].default_value = (0.2, 0.7, 0.2, 1.0)
        gloss = nodes.new("ShaderNodeBsdfGlossy")
        gloss.inputs["Roughness"].default_value = 0.25
        mix = nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = 0.3
        links.new(diff.outputs[0], mix.inputs[1])
        links.new(gloss.outputs[0], mix.inputs[2])
        return mix.outputs[0]
    primitive(bpy.ops.mesh.primitive_cylinder_add, "Cylinder",
              material=shader_material("DiffuseGlossyMix", mix_build, (0.2, 0.7, 0.2)), pass_index=4,
              smooth=True, radius=0.6, depth=1.6, vertices=48, location=(-4.4, -1.6, 0.8))
    primitive(bpy.ops.mesh.primitive_cone_add, "Cone",
              material=principled("Cone", (0.9, 0.8, 0.2), metallic=1.0, roughness=0.3), pass_index=5,
              radius1=0.7, depth=1.5, vertices=48, location=(-2.2, -2.6, 0.75))
    # Principled + Emission through an Add Shader.
    def add_build(nodes, links):
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
        bsdf.inputs["Base Color"].default_value = (0.1, 0.1, 0.1, 1.0)
        emit = nodes.new("ShaderNodeEmission")
        emit.inputs["Color"].default_value = (0.2, 0.6, 1.0, 1.0)
        emit.inputs["Strength"].default_value = 3.0
        add = nodes.new("ShaderNodeAddShader")
        links.new(bsdf.outputs[0], add.inputs[0])
        links.new(emit.outputs[0], add.inputs[1])
        return add.outputs[0]
    torus = primitive(bpy.ops.mesh.primitive_torus_add, "Torus",
                      material=shader_material("GlowingTorus", add_build, (0.2, 0.6, 1.0)), pass_index=6,
                      smooth=True, major_radius=0.6, minor_radius=0.2, location=(0.2, -3.2, 0.2))
    torus.data.use_auto_smooth = True

    # 5x5 sphere grid on the right: roughness left -> right, metallic front -> back.
    sphere_mesh = None
    for i in range(5):
        for j in range(5):
            mat = principled(f"Grid_r{i}_m{j}", (0.9, 0.6, 0.3), metallic=j / 4.0, roughness=i / 4.0)
            if sphere_mesh is None:
                bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=0.35)
                proto = bpy.context.active_object
                for poly in proto.data.polygons:
                    poly.use_smooth = True
                sphere_mesh = proto.data
                sphere_mesh.name = "GridSphere"
                sphere_mesh.materials.append(mat)
                bpy.data.objects.remove(proto)
            obj = bpy.data.objects.new(f"Grid_{i}_{j}", sphere_mesh)
            obj.location = (1.6 + 0.9 * i, -1.8 + 0.9 * j, 0.35)
            obj.pass_index = 10 + 5 * j + i
            link(obj)
            # Object-linked material: all 25 spheres share one mesh.
            obj.material_slots[0].link = 'OBJECT'
            obj.material_slots[0].material = mat

    # Every light type, every area shape.
    add_light("Point", 'POINT', (3.5, -3.5, 3.0), 300.0, (1.0, 0.85, 0.7), shadow_soft_size=0.2)
    add_light("Spot", 'SPOT', (-4.0, -4.0, 5.0), 800.0, (0.8, 0.9, 1.0), target=(-1.5, 0.5, 1.2),
              spot_size=math.radians(35), spot_blend=0.2, shadow_soft_size=0.1)
    add_light("Sun", 'SUN', (0, 0, 10), 1.5, (1.0, 0.95, 0.9), target=(1.5, 1.0, 0), angle=math.radians(2))
    add_light("AreaSquare", 'AREA', (-1.5, -5, 2.5), 150.0, target=(-1.5, 0.5, 1), shape='SQUARE', size=1.0)
    add_light("AreaRect", 'AREA', (7, -3, 3), 200.0, (1.0, 0.7, 0.7), target=(3.4, 0, 0), shape='RECTANGLE',
              size=2.0, size_y=0.5)
    add_light("AreaDisk", 'AREA', (-7, 2, 3), 150.0, (0.7, 1.0, 0.7), target=(-4.5, 0, 0), shape='DISK', size=1.0)
    add_light("AreaEllipse", 'AREA', (0, 6, 4), 150.0, (0.7, 0.7, 1.0), target=(0, 0, 0), shape='ELLIPSE',
              size=1.5, size_y=0.6)

    add_camera(scene, location=(0.0, -12.5, 6.5), target=(0.0, 0.2, 0.6), lens=32.0)
    save(scene, "showcase")


def build_box_room():
    scene = new_scene("BoxRoom")
    set_world(scene, (0.0, 0.0, 0.0))
    white = principled("White", (0.75, 0.75, 0.75), roughness=0.8)
    red = principled("Red", (0.7, 0.08, 0.06), roughness=0.8)
    green = principled("Green", (0.1, 0.6, 0.1), roughness=0.8)
    W, D, H = 6.0, 6.0, 4.0
    walls = [
        ("Floor", (0, 0, 0), (0, 0, 0), (W, D), white),
        ("Ceiling", (0, 0, H), (math.pi, 0, 0), (W, D), white),
        ("BackWall", (0, D / 2, H / 2), (math.pi / 2, 0, 0), (W, H), white),
        ("LeftWall", (-W / 2, 0, H / 2), (0, math.pi / 2, 0), (H, D), red),
        ("RightWall", (W / 2, 0, H / 2), (0, -math.pi / 2, 0), (H, D), green),
    ]
    for index, (name, loc, rot, size, mat) in enumerate(walls, start=1):
        obj = mesh_object(name, plane_mesh(name, *size), location=loc, material=mat, pass_index=index)
        obj.rotation_euler = rot
    tall = primitive(bpy.ops.mesh.primitive_cube_add, "TallBox", material=white, pass_index=10,
                     size=1.0, location=(-1.0, 1.0, 1.25))
    tall.scale = (1.2, 1.2, 2.5)
    tall.rotation_euler = (0, 0, math.radians(20))
    short = primitive(bpy.ops.mesh.primitive_cube_add, "ShortBox", material=white, pass_index=11,
                      size=1.2, location=(1.2, -0.6, 0.6))
    short.rotation_euler = (0, 0, math.radians(-18))
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Ball",
              material=principled("Chrome", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.1), pass_index=12,
              smooth=True, radius=0.5, location=(1.2, -0.6, 1.7), segments=48, ring_count=24)
    add_light("CeilingLight", 'AREA', (0, 0, H - 0.01), 400.0, (1.0, 0.9, 0.8), shape='SQUARE', size=1.5)
    add_light("Bulb", 'POINT', (1.8, -1.8, 3.0), 120.0, (1.0, 0.8, 0.6), shadow_soft_size=0.1)
    add_camera(scene, location=(0, -10.5, H / 2), target=(0, 0, H / 2), lens=38.0)
    save(scene, "box_room")


def build_many_lights(count_x=32, count_y=32):
    scene = new_scene("ManyLights")
    set_world(scene, (0.01, 0.01, 0.01))
    floor_mat = principled("Floor", (0.5, 0.5, 0.5), roughness=0.4)
    mesh_object("Floor", plane_mesh("Floor", 50, 50), material=floor_mat, pass_index=1)
    pillar_mat = principled("Pillar", (0.8, 0.8, 0.8), roughness=0.6)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.25, depth=2.0, vertices=24)
    proto = bpy.context.active_object
    pillar_mesh = proto.data
    pillar_mesh.name = "Pillar"
    pillar_mesh.materials.append(pillar_mat)
    bpy.data.objects.remove(proto)
    for i in range(8):
        for j in range(8):
            obj = bpy.data.objects.new(f"Pillar_{i}_{j}", pillar_mesh)
            obj.location = (-14 + 4 * i, -14 + 4 * j, 1.0)
            obj.pass_index = 2
            link(obj)

    lights = bpy.data.collections.new("Lights")
    scene.collection.children.link(lights)
    rng = random.Random(1234)
    palette = []
    for k in range(16):
        hue = k / 16.0
        r = max(0.0, min(1.0, abs(hue * 6 - 3) - 1))
        g = max(0.0, min(1.0, 2 - abs(hue * 6 - 2)))
        b = max(0.0, min(1.0, 2 - abs(hue * 6 - 4)))
        data = bpy.data.lights.new(f"SmallLight_{k}", 'POINT')
        data.color = (0.2 + 0.8 * r, 0.2 + 0.8 * g, 0.2 + 0.8 * b)
        data.energy = 8.0
        data.shadow_soft_size = 0.05
        # Small fill lights cast no shadows (1024 shadow maps would dominate
        # any renderer); the moon below is the one shadowed key light.
        data.use_shadow = False
        palette.append(data)
    spacing = 1.0
    for i in range(count_x):
        for j in range(count_y):
            obj = bpy.data.objects.new(f"L_{i:02d}_{j:02d}", rng.choice(palette))
            obj.location = ((i - (count_x - 1) / 2) * spacing, (j - (count_y - 1) / 2) * spacing,
                            0.3 + 0.5 * rng.random())
            lights.objects.link(obj)
    add_light("Moon", 'SUN', (0, 0, 20), 0.05, (0.6, 0.7, 1.0), target=(4, 6, 0), angle=math.radians(1.0))
    add_camera(scene, location=(0, -26, 14), target=(0, 0, 0), lens=35.0)
    save(scene, "many_lights")


def _scatter_node_group(instance_object, grid=(101, 100), size=(50.0, 50.0)):
    ng = bpy.data.node_groups.new("Scatter", 'GeometryNodeTree')
    ng.inputs.new('NodeSocketGeometry', "Geometry")
    ng.outputs.new('NodeSocketGeometry', "Geometry")
    nodes, links = ng.nodes, ng.links
    group_out = nodes.new("NodeGroupOutput")
    nodes.new("NodeGroupInput")
    grid_node = nodes.new("GeometryNodeMeshGrid")
    grid_node.inputs["Size X"].default_value = size[0]
    grid_node.inputs["Size Y"].default_value = size[1]
    grid_node.inputs["Vertices X"].default_value = grid[0]
    grid_node.inputs["Vertices Y"].default_value = grid[1]
    info = nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = instance_object
    info.inputs["As Instance"].default_value = True
    iop = nodes.new("GeometryNodeInstanceOnPoints")
    rot = nodes.new("FunctionNodeRandomValue")
    rot.data_type = 'FLOAT_VECTOR'
    rot.inputs[0].default_value = (0.0, 0.0, 0.0)        # Min (vector)
    rot.inputs[1].default_value = (0.3, 0.3, 6.2831853)  # Max (vector)
    rot.inputs["Seed"].default_value = 7
    scale = nodes.new("FunctionNodeRandomValue")
    scale.data_type = 'FLOAT'
    scale.inputs[2].default_value = 0.15                  # Min (float)
    scale.inputs[3].default_value = 0.35                  # Max (float)
    scale.inputs["Seed"].default_value = 3
    links.new(grid_node.outputs["Mesh"], iop.inputs["Points"])
    links.new(info.outputs["Geometry"], iop.inputs["Instance"])
    links.new(rot.outputs[0], iop.inputs["Rotation"])
    links.new(scale.outputs[1], iop.inputs["Scale"])
    links.new(iop.outputs["Instances"], group_out.inputs[0])
    return ng


def build_instancing():
    scene = new_scene("Instancing")
    set_world(scene, (0.05, 0.06, 0.08))
    mesh_object("Ground", plane_mesh("Ground", 60, 60),
                material=principled("Ground", (0.35, 0.3, 0.25), roughness=0.9), pass_index=1)

    # Source objects live in a collection that is not linked to the scene:
    # they render only through their instances.
    assets = bpy.data.collections.new("Assets")
    assets.use_fake_user = True
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2, radius=1.0)
    rock = bpy.context.active_object
    rock.name = rock.data.name = "Rock"
    rock.data.materials.append(principled("Rock", (0.5, 0.45, 0.4), roughness=0.6))
    rock.pass_index = 2
    scene.collection.objects.unlink(rock)
    assets.objects.link(rock)

    tree = bpy.data.collections.new("Tree")
    tree.use_fake_user = True
    bpy.ops.mesh.primitive_cylinder_add(radius=0.15, depth=1.0, vertices=12, location=(0, 0, 0.5))
    trunk = bpy.context.active_object
    trunk.name = trunk.data.name = "Trunk"
    trunk.data.materials.append(principled("Bark", (0.3, 0.18, 0.08), roughness=0.8))
    trunk.pass_index = 3
    bpy.ops.mesh.primitive_cone_add(radius1=0.8, depth=2.0, vertices=16, location=(0, 0, 2.0))
    crown = bpy.context.active_object
    crown.name = crown.data.name = "Crown"
    crown.data.materials.append(principled("Leaves", (0.1, 0.45, 0.12), roughness=0.7))
    crown.pass_index = 4
    for obj in (trunk, crown):
        scene.collection.objects.unlink(obj)
        tree.objects.link(obj)

    # >= 10 000 geometry-nodes instances of the rock.
    scatter = mesh_object("Scatter", bpy.data.meshes.new("ScatterBase"), pass_index=5)
    mod = scatter.modifiers.new("Scatter", 'NODES')
    mod.node_group = _scatter_node_group(rock)

    # Plus collection instances of the tree on a ring.
    for k in range(24):
        angle = 2 * math.pi * k / 24
        empty = bpy.data.objects.new(f"Tree_{k:02d}", None)
        empty.instance_type = 'COLLECTION'
        empty.instance_collection = tree
        empty.location = (18 * math.cos(angle), 18 * math.sin(angle), 0)
        empty.scale = (1.5, 1.5, 1.5)
        link(empty)

    add_light("Sun", 'SUN', (0, 0, 20), 3.0, (1.0, 0.95, 0.85), target=(3, 2, 0), angle=math.radians(1.0))
    add_light("Fill", 'POINT', (-10, -10, 8), 2000.0, (0.7, 0.8, 1.0), shadow_soft_size=1.0)
    add_camera(scene, location=(0, -38, 22), target=(0, 0, 0), lens=35.0)

    depsgraph = bpy.context.evaluated_depsgraph_get()
    count = sum(1 for inst in depsgraph.object_instances if inst.is_instance)
    print(f"generate_samples: instancing scene has {count} instances")
    assert count >= 10000, count
    save(scene, "instancing")


def build_analytic():
    scene = analytic_scene("Analytic", resolution=(320, 180))
    scene.frame_end = 3
    save(scene, "analytic")


def build_turntable():
    """The analytic scene as a 24-frame animation for farm renders
    (scripts/cluster/): the camera orbits once, SphereB bobs."""
    scene = analytic_scene("Turntable", resolution=(320, 180))
    scene.frame_start, scene.frame_end = 1, 24
    orbit = link(bpy.data.objects.new("Orbit", None))
    scene.camera.parent = orbit
    for frame, angle in ((1, 0.0), (25, 2.0 * math.pi)):
        orbit.rotation_euler.z = angle
        orbit.keyframe_insert("rotation_euler", index=2, frame=frame)
    sphere = bpy.data.objects["SphereB"]
    for frame, z in ((1, 1.5), (12, 2.5), (24, 1.5)):
        sphere.location.z = z
        sphere.keyframe_insert("location", index=2, frame=frame)
    for obj in (orbit, sphere):
        for fcurve in obj.animation_data.action.fcurves:
            for key in fcurve.keyframe_points:
                key.interpolation = 'LINEAR'
    scene.frame_set(1)
    save(scene, "turntable")


def analytic_scene(name, resolution):
    A = ANALYTIC
    scene = new_scene(name, resolution=resolution)
    set_world(scene, (0.05, 0.05, 0.05))

    floor = A["floor"]
    mesh_object("Floor", plane_mesh("Floor", *floor["size"]), location=floor["center"],
                material=principled("MatFloor", (0.6, 0.6, 0.6), pass_index=floor["material_pass_index"]),
                pass_index=floor["pass_index"])
    wall = A["wall"]
    obj = mesh_object("Wall", plane_mesh("Wall", *wall["size"]), location=wall["center"],
                      material=principled("MatWall", (0.7, 0.7, 0.5), pass_index=wall["material_pass_index"]),
                      pass_index=wall["pass_index"])
    obj.rotation_euler = (math.pi / 2, 0, 0)   # plane normal +Z -> -Y
    for s in A["spheres"]:
        mat = principled("Mat" + s["name"], (0.2, 0.4, 0.8), roughness=0.3, pass_index=s["material_pass_index"])
        primitive(bpy.ops.mesh.primitive_uv_sphere_add, s["name"], material=mat, pass_index=s["pass_index"],
                  smooth=True, segments=64, ring_count=32, radius=s["radius"], location=s["center"])
    box = A["box"]
    cube = primitive(bpy.ops.mesh.primitive_cube_add, box["name"], pass_index=box["pass_index"],
                     size=box["size"], location=box["center"])
    cube.data.materials.append(principled("MatBoxSide", (0.8, 0.2, 0.2), pass_index=box["material_pass_index"][0]))
    cube.data.materials.append(principled("MatBoxTop", (0.2, 0.8, 0.2), pass_index=box["material_pass_index"][1]))
    for poly in cube.data.polygons:
        poly.material_index = 1 if poly.normal.z > 0.5 else 0

    add_light("Sun", 'SUN', (0, 0, 10), 3.0, target=(1, 2, 0), angle=math.radians(0.526))
    add_light("Point", 'POINT', (2, -4, 4), 500.0, shadow_soft_size=0.25)
    cam = A["camera"]
    add_camera(scene, "Camera", cam["location"], cam["target"], lens=cam["lens"])
    ortho = A["camera_ortho"]
    add_camera(scene, "CameraOrtho", ortho["location"], ortho["target"], ortho_scale=ortho["ortho_scale"],
               active=False)
    scene["analytic"] = repr(A)
    return scene


def _node(nodes, kind, inputs=None, **props):
    node = nodes.new(kind)
    for key, value in props.items():
        setattr(node, key, value)
    for key, value in (inputs or {}).items():
        node.inputs[key].default_value = value
    return node


def build_materials():
    """Everyday node materials (textures, UVs, bump, procedurals, vertex
    colours, Object Info, emission): what node-tree support renders."""
    scene = new_scene("Materials")
    set_world(scene, (0.03, 0.03, 0.035))
    add_camera(scene, location=(0.0, -11.0, 4.5), target=(0.0, 0.0, 0.9), lens=45.0)
    add_light("Sun", "SUN", (4, -4, 8), 3.0, target=(0, 0, 0), angle=0.05)
    add_light("Key", "AREA", (-4, -3, 5), 600.0, target=(0, 0, 0.5), size=2.0)

    def floor_material(nodes, links):  # Brick through Hue/Saturation, Voronoi bump
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled", {"Roughness": 0.6})
        brick = _node(nodes, "ShaderNodeTexBrick", {"Scale": 3.0, "Color1": (0.55, 0.22, 0.12, 1),
                                                     "Color2": (0.35, 0.15, 0.1, 1)})
        hue = _node(nodes, "ShaderNodeHueSaturation", {"Saturation": 0.8})
        links.new(brick.outputs["Color"], hue.inputs["Color"])
        links.new(hue.outputs["Color"], bsdf.inputs["Base Color"])
        bump = _node(nodes, "ShaderNodeBump", {"Distance": 0.02})
        links.new(brick.outputs["Fac"], bump.inputs["Height"])
        links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
        return bsdf.outputs[0]

    floor = mesh_object("Floor", plane_mesh("Floor", 16.0, 16.0), material=shader_material("Bricks", floor_material))
    floor.data.uv_layers[0].data.foreach_set("uv", [c * 4 for c in (0, 0, 1, 0, 1, 1, 0, 1)])

    def marble(nodes, links):  # Noise -> ColorRamp base colour, Musgrave bump
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled", {"Roughness": 0.25})
        noise = _node(nodes, "ShaderNodeTexNoise", {"Scale": 3.0, "Detail": 6.0, "Distortion": 2.0})
        ramp = _node(nodes, "ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (0.05, 0.07, 0.12, 1)
        ramp.color_ramp.elements[1].color = (0.9, 0.88, 0.8, 1)
        links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
        musgrave = _node(nodes, "ShaderNodeTexMusgrave", {"Scale": 8.0})
        bump = _node(nodes, "ShaderNodeBump", {"Distance": 0.05, "Strength": 0.3})
        links.new(musgrave.outputs["Fac"], bump.inputs["Height"])
        links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
        return bsdf.outputs[0]

    primitive(bpy.ops.mesh.primitive_monkey_add, "Suzanne", shader_material("Marble", marble), smooth=True,
              location=(-3.0, 0.0, 1.0), rotation=(0.0, 0.0, 0.4))

    def grid(nodes, links):  # image texture (generated colour grid) through UV + Mapping
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled", {"Roughness": 0.4})
        image = bpy.data.images.new("ColorGrid", 1024, 1024)
        image.generated_type = 'COLOR_GRID'
        tex = _node(nodes, "ShaderNodeTexImage", image=image)
        coords = _node(nodes, "ShaderNodeTexCoord")
        mapping = _node(nodes, "ShaderNodeMapping", {"Scale": (2.0, 1.0, 1.0)})
        links.new(coords.outputs["UV"], mapping.inputs["Vector"])
        links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
        links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        return bsdf.outputs[0]

    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "GridSphere", shader_material("Grid", grid), smooth=True,
              location=(-1.0, 1.5, 1.0), radius=1.0)

    def layered(nodes, links):  # Layer Weight mixing Diffuse and Glossy
        diffuse = _node(nodes, "ShaderNodeBsdfDiffuse", {"Color": (0.1, 0.3, 0.7, 1)})
        glossy = _node(nodes, "ShaderNodeBsdfGlossy", {"Roughness": 0.15})
        weight = _node(nodes, "ShaderNodeLayerWeight", {"Blend": 0.3})
        mix = _node(nodes, "ShaderNodeMixShader")
        links.new(weight.outputs["Fresnel"], mix.inputs["Fac"])
        links.new(diffuse.outputs[0], mix.inputs[1])
        links.new(glossy.outputs[0], mix.inputs[2])
        return mix.outputs[0]

    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Coated", shader_material("Coated", layered), smooth=True,
              location=(1.2, 0.5, 1.0), radius=1.0)

    def random_colour(nodes, links):  # Object Info Random through a ColorRamp
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled")
        info = _node(nodes, "ShaderNodeObjectInfo")
        ramp = _node(nodes, "ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (0.9, 0.2, 0.1, 1)
        ramp.color_ramp.elements[1].color = (0.1, 0.4, 0.9, 1)
        links.new(info.outputs["Random"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
        return bsdf.outputs[0]

    blocks = shader_material("RandomBlocks", random_colour)
    for k in range(5):
        primitive(bpy.ops.mesh.primitive_cube_add, f"Block{k}", blocks, size=0.5,
                  location=(3.0 + 0.6 * (k % 2), -2.0 + 0.8 * k, 0.25))

    def painted(nodes, links):  # vertex colours
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled")
        colour = _node(nodes, "ShaderNodeVertexColor", layer_name="Paint")
        links.new(colour.outputs["Color"], bsdf.inputs["Base Color"])
        return bsdf.outputs[0]

    cube = primitive(bpy.ops.mesh.primitive_cube_add, "Painted", shader_material("Painted", painted), size=1.2,
                     location=(1.5, -2.5, 0.6), rotation=(0.0, 0.0, 0.6))
    paint = cube.data.color_attributes.new("Paint", 'FLOAT_COLOR', 'POINT')
    for i, v in enumerate(cube.data.vertices):
        paint.data[i].color = (0.5 + 0.5 * v.co.x / 0.6, 0.5 + 0.5 * v.co.y / 0.6, 0.5 + 0.5 * v.co.z / 0.6, 1.0)

    def panel(nodes, links):  # an emissive checker panel
        emission = _node(nodes, "ShaderNodeEmission", {"Strength": 4.0})
        checker = _node(nodes, "ShaderNodeTexChecker", {"Scale": 6.0, "Color1": (1.0, 0.6, 0.2, 1),
                                                         "Color2": (0.02, 0.02, 0.02, 1)})
        links.new(checker.outputs["Color"], emission.inputs["Color"])
        return emission.outputs[0]

    mesh_object("Panel", plane_mesh("Panel", 3.0, 1.5), material=shader_material("Panel", panel),
                location=(0.0, 4.0, 1.5)).rotation_euler = (1.5708, 0.0, 0.0)
    save(scene, "materials")


def leaf_image(size=128):
    """A leaf cut-out (RGBA): green with a lighter midrib, alpha 1 inside an
    almond-shaped blade and a stem, 0 outside; packed into the .blend."""
    image = bpy.data.images.new("Leaf", size, size, alpha=True)
    pixels = []
    for j in range(size):
        v = (j + 0.5) / size  # 0 at the stem end, 1 at the tip
        for i in range(size):
            u = (i + 0.5) / size * 2.0 - 1.0
            half_width = 0.8 * math.sin(math.pi * min(max((v - 0.12) / 0.86, 0.0), 1.0)) ** 0.8
            blade = abs(u) < half_width
            stem = v < 0.14 and abs(u) < 0.04
            rib = abs(u) < 0.03 + 0.02 * (1.0 - v)
            g = 0.65 if rib else 0.45 + 0.1 * math.cos(12.0 * (v + abs(u)))
            pixels += [0.15 if rib else 0.1, g, 0.08, 1.0 if (blade or stem) else 0.0]
    image.pixels = pixels
    image.pack()
    return image


def build_transparency():
    """Transparency as Cycles renders it (issue: transparency): a floor and
    coloured blocks under a sun, seen through a leaf cut-out (image alpha),
    two panes of constant alpha 0.3 and 0.4, a sphere mixing Diffuse with a
    Transparent BSDF, and two overlapping panes of alpha 0.5; their partial
    shadows fall on the floor."""
    scene = new_scene("Transparency", resolution=(320, 180))
    set_world(scene, (0.08, 0.08, 0.1))
    scene.cycles.transparent_max_bounces = 8  # Blender's default; this engine does not limit layers
    upright = (math.pi / 2, 0.0, 0.0)
    mesh_object("Floor", plane_mesh("Floor", 30, 30), material=principled("Floor", (0.7, 0.7, 0.7), roughness=0.8),
                pass_index=1)
    for k, colour in enumerate(((0.8, 0.15, 0.1), (0.1, 0.3, 0.8), (0.9, 0.7, 0.1), (0.2, 0.7, 0.3))):
        primitive(bpy.ops.mesh.primitive_cube_add, f"Block{k}", principled(f"Block{k}", colour, roughness=0.4),
                  pass_index=2, size=1.0, location=(-3.0 + 2.0 * k, 2.5, 0.5))

    def leaf(nodes, links):
        bsdf = _node(nodes, "ShaderNodeBsdfPrincipled", {"Roughness": 0.6})
        tex = _node(nodes, "ShaderNodeTexImage", image=leaf_image())
        links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
        links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
        return bsdf.outputs[0]

    obj = mesh_object("Leaf", plane_mesh("Leaf", 1.6, 1.6), material=shader_material("Leaf", leaf),
                      location=(-3.0, 0.0, 1.2), pass_index=3)
    obj.rotation_euler = (upright[0], 0.0, math.radians(15))
    for name, alpha, x, colour in (("Pane03", 0.3, -1.2, (0.2, 0.8, 0.9)), ("Pane04", 0.4, 0.4, (0.9, 0.3, 0.7))):
        mat = principled(name, colour, roughness=0.3, inputs={"Alpha": alpha})
        mesh_object(name, plane_mesh(name, 1.3, 1.6), material=mat, location=(x, 0.0, 0.9),
                    pass_index=4).rotation_euler = upright

    def mix(nodes, links):
        diffuse = _node(nodes, "ShaderNodeBsdfDiffuse", {"Color": (0.9, 0.8, 0.2, 1.0)})
        transparent = _node(nodes, "ShaderNodeBsdfTransparent")
        mixer = _node(nodes, "ShaderNodeMixShader", {"Fac": 0.35})
        links.new(diffuse.outputs[0], mixer.inputs[1])
        links.new(transparent.outputs[0], mixer.inputs[2])
        return mixer.outputs[0]

    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "MixSphere", shader_material("DiffuseTransparent", mix),
              pass_index=5, smooth=True, radius=0.7, location=(1.9, 0.2, 0.75), segments=48, ring_count=24)
    half = principled("Pane05", (0.3, 0.4, 0.9), roughness=0.3, inputs={"Alpha": 0.5})
    for name, y in (("PaneA", -0.3), ("PaneB", 0.1)):
        mesh_object(name, plane_mesh(name, 1.2, 1.6), material=half, location=(3.4, y, 0.9),
                    pass_index=6).rotation_euler = upright
    add_light("Sun", 'SUN', (0, 0, 10), 3.0, target=(-1.5, 3.0, 0.0), angle=math.radians(1.0))
    add_camera(scene, location=(0.0, -8.0, 2.6), target=(0.2, 0.5, 0.8), lens=35.0)
    save(scene, "transparency")


def build_hdri_studio():
    """Lit only by one of Blender's bundled studio HDRIs (Environment
    Texture, rotated 60 degrees by a Mapping node): a floor, a diffuse and a
    rough metal sphere, a glossy Suzanne. The image is referenced from
    Blender's datafiles (Debian: /usr/share/blender), not packed."""
    scene = new_scene("HdriStudio")
    world = set_world(scene, (0.3, 0.3, 0.3))
    nt = world.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(
        os.path.join(bpy.utils.system_resource('DATAFILES'), "studiolights", "world", "forest.exr"))
    coords = nt.nodes.new("ShaderNodeTexCoord")
    mapping = nt.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(60))
    nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    nt.links.new(env.outputs["Color"], nt.nodes["Background"].inputs["Color"])
    mesh_object("Floor", plane_mesh("Floor", 12.0, 12.0), material=principled("Floor", (0.6, 0.6, 0.6),
                                                                               roughness=0.7), pass_index=1)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Diffuse", material=principled(
        "Clay", (0.75, 0.55, 0.4), roughness=1.0, specular=0.0), pass_index=2, smooth=True,
        radius=0.8, location=(-1.8, 0.0, 0.8), segments=64, ring_count=32)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Metal", material=principled(
        "Brushed", (0.9, 0.65, 0.35), metallic=1.0, roughness=0.5), pass_index=3, smooth=True,
        radius=0.8, location=(1.8, 0.0, 0.8), segments=64, ring_count=32)
    suzanne = primitive(bpy.ops.mesh.primitive_monkey_add, "Suzanne", material=principled(
        "Glaze", (0.1, 0.25, 0.6), roughness=0.25), pass_index=4, smooth=True, size=1.2,
        location=(0.0, 1.2, 0.75))
    suzanne.rotation_euler = (0.0, 0.0, math.radians(-20))
    modifier = suzanne.modifiers.new("Subdivision", 'SUBSURF')
    modifier.levels = modifier.render_levels = 1
    add_camera(scene, location=(0, -7.5, 2.6), target=(0, 0, 0.8), lens=40.0)
    save(scene, "hdri_studio")


def build_sky_sun():
    """Lit only by a Nishita Sky Texture (Blender 3.4's default model) with
    its sun disc, low in the afternoon: a floor, a diffuse sphere, a rough
    metal sphere and a box; the sky fills the top of the frame."""
    scene = new_scene("SkySun", resolution=(320, 180))
    world = set_world(scene, (0.3, 0.4, 0.6))
    nt = world.node_tree
    sky = nt.nodes.new("ShaderNodeTexSky")
    sky.sky_type = 'NISHITA'
    sky.sun_elevation = math.radians(20.0)
    sky.sun_rotation = math.radians(140.0)
    sky.sun_size = math.radians(1.5)
    nt.links.new(sky.outputs["Color"], nt.nodes["Background"].inputs["Color"])
    nt.nodes["Background"].inputs["Strength"].default_value = 0.1
    mesh_object("Floor", plane_mesh("Floor", 40.0, 40.0), material=principled("Floor", (0.55, 0.55, 0.5),
                                                                               roughness=0.8), pass_index=1)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Diffuse", material=principled(
        "Clay", (0.8, 0.5, 0.35), roughness=1.0, specular=0.0), pass_index=2, smooth=True,
        radius=0.8, location=(-1.6, 0.5, 0.8), segments=64, ring_count=32)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Metal", material=principled(
        "Brushed", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.35), pass_index=3, smooth=True,
        radius=0.8, location=(1.6, 0.5, 0.8), segments=64, ring_count=32)
    box = primitive(bpy.ops.mesh.primitive_cube_add, "Box", material=principled("Box", (0.2, 0.35, 0.7),
                                                                                roughness=0.5),
                    pass_index=4, size=1.0, location=(0.0, 2.2, 0.5))
    box.rotation_euler = (0.0, 0.0, math.radians(30))
    add_camera(scene, location=(0, -7.0, 1.6), target=(0, 0.8, 1.2), lens=30.0)
    save(scene, "sky_sun")


def build_emitters():
    """Lit only by emissive meshes (a black world): a constant panel over the
    floor, a standing panel whose emission is an orange/blue Checker
    (baked), and 5000 small emissive triangles scattered in a ring above
    the scene (fairy lights, one mesh); a diffuse sphere, a glossy Suzanne
    and a box receive and cast the light."""
    import random
    scene = new_scene("Emitters", resolution=(320, 180))
    set_world(scene, (0.0, 0.0, 0.0))
    mesh_object("Floor", plane_mesh("Floor", 14.0, 14.0), material=principled("Floor", (0.6, 0.6, 0.6),
                                                                               roughness=0.6), pass_index=1)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "Diffuse", material=principled(
        "Clay", (0.8, 0.8, 0.8), roughness=1.0, specular=0.0), pass_index=2, smooth=True,
        radius=0.7, location=(-1.5, 0.3, 0.7), segments=48, ring_count=24)
    suzanne = primitive(bpy.ops.mesh.primitive_monkey_add, "Suzanne", material=principled(
        "Glaze", (0.7, 0.3, 0.2), roughness=0.3), pass_index=3, smooth=True, size=1.2,
        location=(1.4, 0.4, 0.7))
    suzanne.rotation_euler = (0.0, 0.0, math.radians(-20))
    primitive(bpy.ops.mesh.primitive_cube_add, "Box", material=principled("Box", (0.3, 0.5, 0.3), roughness=0.5),
              pass_index=4, size=0.8, location=(0.0, -0.8, 0.4))
    # A constant panel facing down, 2.6 above the floor.
    panel = mesh_object("Panel", plane_mesh("Panel", 1.6, 1.0), location=(-0.8, 0.0, 2.6), pass_index=5,
                        material=shader_material("PanelLight", lambda nodes, links: _node(
                            nodes, "ShaderNodeEmission", {"Color": (1.0, 0.92, 0.8, 1.0), "Strength": 4.0}
                        ).outputs[0], viewport=(1.0, 0.92, 0.8)))
    panel.rotation_euler = (math.pi, 0.0, 0.0)

    def checker(nodes, links):
        emit = _node(nodes, "ShaderNodeEmission", {"Strength": 6.0})
        tex = _node(nodes, "ShaderNodeTexChecker", {"Scale": 2.0, "Color1": (1.0, 0.45, 0.1, 1.0),
                                                    "Color2": (0.1, 0.3, 1.0, 1.0)})
        links.new(tex.outputs["Color"], emit.inputs["Color"])
        return emit.outputs[0]

    standing = mesh_object("Screen", plane_mesh("Screen", 2.4, 1.4), location=(0.3, 2.6, 1.2), pass_index=6,
                           material=shader_material("ScreenLight", checker, viewport=(0.6, 0.4, 0.6)))
    standing.rotation_euler = (math.pi / 2, 0.0, 0.0)
    # 5000 small triangles (edge ~4 cm) in a ring of radius 3 at heights 2.2-3.
    rng = random.Random(7)
    verts, faces = [], []
    for k in range(5000):
        angle = rng.uniform(0.0, 2.0 * math.pi)
        radius = 3.0 + rng.uniform(-0.3, 0.3)
        c = (radius * math.cos(angle), radius * math.sin(angle), rng.uniform(2.2, 3.0))
        for j in range(3):
            a = rng.uniform(0.0, 2.0 * math.pi)
            verts.append((c[0] + 0.025 * math.cos(a), c[1] + 0.025 * math.sin(a), c[2] + rng.uniform(-0.02, 0.02)))
        faces.append((3 * k, 3 * k + 1, 3 * k + 2))
    mesh = bpy.data.meshes.new("FairyLights")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    mesh_object("FairyLights", mesh, pass_index=7, material=shader_material(
        "FairyLight", lambda nodes, links: _node(
            nodes, "ShaderNodeEmission", {"Color": (1.0, 0.8, 0.5, 1.0), "Strength": 60.0}).outputs[0],
        viewport=(1.0, 0.8, 0.5)))
    add_camera(scene, location=(0, -7.5, 3.0), target=(0, 0.6, 0.9), lens=32.0)
    save(scene, "emitters")


BUILDERS = {
    "hdri_studio": build_hdri_studio,
    "sky_sun": build_sky_sun,
    "emitters": build_emitters,
    "materials": build_materials,
    "showcase": build_showcase,
    "box_room": build_box_room,
    "many_lights": build_many_lights,
    "instancing": build_instancing,
    "analytic": build_analytic,
    "turntable": build_turntable,
    "transparency": build_transparency,
}


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    names = argv or list(BUILDERS)
    for name in names:
        if name not in BUILDERS:
            raise SystemExit(f"unknown sample '{name}', choose from {', '.join(BUILDERS)}")
        BUILDERS[name]()


main()
