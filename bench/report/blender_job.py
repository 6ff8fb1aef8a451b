"""Runs INSIDE Blender: render one scene with one engine at several sample
counts, time each render, measure peak memory, save Combined as EXR.

    blender -b --factory-startup [--addons deferred_render] SCENE.blend \
        --python-exit-code 1 --python bench/report/blender_job.py -- JOB.json

JOB.json (written by run_report.py):
    {"engine": "CYCLES" | "BLENDER_EEVEE" | "DEFERRED_RENDER",
     "target_width": 320,            # resolution_percentage chosen so width ~ this
     "warmup": true,                 # one untimed-for-the-table render first
     "eevee": {...}, "cycles": {...} # engine settings (see apply_* below)
     "index_pass": false,            # also keep IndexOB (multilayer EXR; the reference)
     "no_shadows": false,            # nothing occludes: see disable_shadows()
     "deferred_settings": {...},     # scene.deferred_render properties to set (e.g. shadow_method)
     "renders": [{"samples": 16, "seed": 7, "out": "/abs/x.exr", "min_reps": 1}, ...],
     "results": "/abs/results.json"}

How time is measured: time.perf_counter() around bpy.ops.render.render()
(no write_still; the EXR is saved afterwards with save_render, untimed). So
Blender start-up and file loading are excluded; the render operator's own
work is included: the render depsgraph evaluation, the engine's scene
export/sync (Cycles BVH build, EEVEE shader compilation if not cached, our
GL context start and upload) and the sampling itself. With "warmup" the
first render (at the first sample count) is done once before the measured
ones, so in-process caches (EEVEE's compiled shaders, Cycles' kernels, our
shader cache if any) are warm; its time is reported as cold_s. Renders
faster than 2 s are repeated (3 times in all) and the fastest is kept
(other work on the 2 cores only ever adds time).

How memory is measured: before each render the process' peak RSS (VmHWM) is
reset through /proc/self/clear_refs ("5"); after it VmHWM is read. That is
the peak resident memory of the whole Blender process during that render
(on llvmpipe the "GPU" memory of EEVEE and of our engine is process memory
too, so it is counted). RSS before the render is reported as well, and the
1-minute load average before it (other processes on the 2 cores skew times).
"""

import json
import os
import sys
import time

import bpy


def proc_status_mb(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def reset_peak_rss():
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def only_combined(scene, index_pass=False):
    """Render just the Combined pass of one view layer (same work for all
    engines); the reference also keeps IndexOB for the per-object table."""
    active = bpy.context.view_layer
    for layer in scene.view_layers:
        layer.use = layer == active
    for name in dir(active):
        if name.startswith("use_pass_") and name != "use_pass_combined":
            try:
                setattr(active, name, False)
            except (AttributeError, TypeError):
                pass
    active.use_pass_combined = True
    active.use_pass_object_index = bool(index_pass)
    return active


def disable_shadows():
    """Unoccluded variant of the reference: no object blocks any ray but the
    camera's, so lights and the world light every surface as the Deferred
    engine does while it has no shadows. visible_shadow alone is not enough:
    Cycles combines light sampling with BSDF-sampled rays (MIS) also at
    max_bounces 0, and a BSDF ray that hits an object loses the world's
    light; so diffuse/glossy/transmission visibility go off too (lights keep
    theirs)."""
    for ob in bpy.data.objects:
        if ob.type == 'LIGHT':
            continue
        for flag in ("visible_shadow", "visible_diffuse", "visible_glossy", "visible_transmission",
                     "visible_volume_scatter"):
            if hasattr(ob, flag):
                setattr(ob, flag, False)
    for light in bpy.data.lights:
        if hasattr(light, "cycles"):
            light.cycles.cast_shadow = False
        light.use_shadow = False


def pass_index_names(depsgraph):
    """{pass_index: sorted object names} of the rendered mesh objects."""
    names = {}
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.type in ('MESH', 'CURVE', 'SURFACE', 'META', 'FONT'):
            key = str(ob.pass_index)
            names.setdefault(key, set()).add(ob.original.name if ob.original else ob.name)
    return {k: sorted(v)[:8] + (["..."] if len(v) > 8 else []) for k, v in names.items()}


def apply_common(scene, job):
    r = scene.render
    width = job.get("target_width") or r.resolution_x
    r.resolution_percentage = max(1, min(100, round(100.0 * width / r.resolution_x)))
    r.use_border = False
    r.use_compositing = False
    r.use_sequencer = False
    r.use_motion_blur = False
    r.film_transparent = bool(r.film_transparent)
    # One pixel filter width for all engines: Cycles reads its own
    # cycles.filter_width, EEVEE and the Deferred engine read render.filter_size.
    if hasattr(scene, "cycles"):
        scene.cycles.filter_width = r.filter_size
        scene.cycles.pixel_filter_type = 'BLACKMAN_HARRIS'
    return (r.resolution_x * r.resolution_percentage // 100,
            r.resolution_y * r.resolution_percentage // 100)


def apply_cycles(scene, settings):
    cy = scene.cycles
    cy.device = 'CPU'
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.use_animated_seed = False
    cy.max_bounces = 0
    cy.diffuse_bounces = cy.glossy_bounces = cy.transmission_bounces = 0
    cy.volume_bounces = 0
    # Transparent surfaces do not count against max_bounces (REFERENCE.md);
    # they have their own limit, which at 0 makes them black. Blender's
    # default, as the engine does not limit layers.
    cy.transparent_max_bounces = 8
    cy.caustics_reflective = cy.caustics_refractive = False
    cy.use_light_tree = False if hasattr(cy, "use_light_tree") else None
    for key, value in (settings or {}).items():
        setattr(cy, key, value)
    scene.render.threads_mode = 'AUTO'


def apply_eevee(scene, settings):
    ee = scene.eevee
    # shared/REFERENCE.md section 2, fair settings.
    ee.light_threshold = 1e-4
    ee.use_soft_shadows = True
    ee.use_shadow_high_bitdepth = True
    ee.use_gtao = False
    ee.use_ssr = False
    ee.use_bloom = False
    ee.use_motion_blur = False
    ee.use_volumetric_lights = False
    for key, value in (settings or {}).items():
        setattr(ee, key, value)


def set_samples(scene, engine, samples, seed):
    if engine == 'CYCLES':
        scene.cycles.samples = samples
        scene.cycles.seed = seed
    elif engine == 'BLENDER_EEVEE':
        scene.eevee.taa_render_samples = samples
    elif engine == 'DEFERRED_RENDER':
        scene.deferred_render.samples = samples
    else:
        raise ValueError(engine)


def render_once(scene):
    load_before = os.getloadavg()[0]
    reset_ok = reset_peak_rss()
    rss_before = proc_status_mb("VmRSS")
    t0 = time.perf_counter()
    bpy.ops.render.render()
    dt = time.perf_counter() - t0
    peak = proc_status_mb("VmHWM") if reset_ok else float("nan")
    return dt, rss_before, peak, load_before


def save_combined(scene, path, multilayer=False):
    img = scene.render.image_settings
    img.file_format = 'OPEN_EXR_MULTILAYER' if multilayer else 'OPEN_EXR'
    img.color_mode = 'RGBA'
    img.color_depth = '32'
    img.exr_codec = 'ZIP'
    os.makedirs(os.path.dirname(path), exist_ok=True)
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    if not os.path.exists(path):
        raise RuntimeError(f"save_render wrote nothing at {path}")


def main():
    job_path = sys.argv[sys.argv.index("--") + 1]
    with open(job_path) as f:
        job = json.load(f)
    engine = job["engine"]
    scene = bpy.context.scene
    scene.render.engine = engine
    if scene.render.engine != engine:
        raise RuntimeError(f"engine {engine} not available")
    if engine == 'DEFERRED_RENDER' and not hasattr(scene, "deferred_render"):
        raise RuntimeError("the deferred_render add-on is not loaded")
    only_combined(scene, job.get("index_pass", False))
    size = apply_common(scene, job)
    if hasattr(scene, "cycles"):
        apply_cycles(scene, job.get("cycles"))
    apply_eevee(scene, job.get("eevee"))
    if job.get("no_shadows"):
        disable_shadows()
    for key, value in (job.get("deferred_settings") or {}).items():
        setattr(scene.deferred_render, key, value)

    out = {"engine": engine, "blend": bpy.data.filepath, "width": size[0], "height": size[1],
           "percentage": scene.render.resolution_percentage, "filter_size": scene.render.filter_size,
           "blender": bpy.app.version_string, "rss_loaded_mb": proc_status_mb("VmRSS"),
           "renders": []}
    if engine == 'DEFERRED_RENDER':
        dr = scene.deferred_render
        out["deferred"] = {k: getattr(dr, k) for k in dir(dr)
                           if not k.startswith(("_", "bl_", "rna_")) and k not in ("name",)
                           and isinstance(getattr(dr, k), (int, float, bool, str))}
    if engine == 'BLENDER_EEVEE':
        ee = scene.eevee
        out["eevee"] = {k: getattr(ee, k) for k in (
            "light_threshold", "use_soft_shadows", "shadow_cube_size", "shadow_cascade_size",
            "use_shadow_high_bitdepth", "use_gtao", "use_ssr", "use_bloom")}
    cold = None
    renders = job["renders"]
    if job.get("warmup") and renders:
        first = renders[0]
        set_samples(scene, engine, first["samples"], first.get("seed", 0))
        dt, _, peak, _ = render_once(scene)
        cold = {"samples": first["samples"], "seconds": dt, "peak_rss_mb": peak}
        print(f"report_job: {engine} warm-up {first['samples']} samples: {dt:.3f} s", flush=True)
    out["cold"] = cold
    for spec in renders:
        set_samples(scene, engine, spec["samples"], spec.get("seed", 0))
        times, peaks, befores, loads = [], [], [], []
        while True:
            dt, before, peak, load = render_once(scene)
            times.append(dt)
            peaks.append(peak)
            befores.append(before)
            loads.append(load)
            reps = max(int(spec.get("min_reps", 1)), 3 if times[0] < 2.0 else 1)
            if len(times) >= reps:
                break
        save_combined(scene, spec["out"], multilayer=job.get("index_pass", False))
        entry = {"samples": spec["samples"], "seed": spec.get("seed", 0), "out": spec["out"],
                 "seconds": min(times), "all_seconds": times,
                 "peak_rss_mb": max(peaks), "rss_before_mb": min(befores),
                 "loadavg_1min_before": max(loads)}
        out["renders"].append(entry)
        print(f"report_job: {engine} {spec['samples']} samples: {entry['seconds']:.3f} s "
              f"(runs {', '.join(f'{t:.3f}' for t in times)}), peak RSS {entry['peak_rss_mb']:.0f} MB",
              flush=True)
        with open(job["results"], "w") as f:   # partial results survive a crash
            json.dump(out, f, indent=1)
    if job.get("index_pass"):
        out["pass_index_names"] = pass_index_names(bpy.context.evaluated_depsgraph_get())
    with open(job["results"], "w") as f:
        json.dump(out, f, indent=1)


main()
