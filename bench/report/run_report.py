#!/usr/bin/python3
"""Speed against error: the Deferred engine beside EEVEE and Cycles, against
a cached Cycles reference, on the sample scenes (and any .blend given).

    /usr/bin/python3 bench/report/run_report.py [--scenes showcase box_room ...] \
        [extra.blend ...] [--out bench/report/out] [--cache bench/report/cache]

Needs: Blender 3.4 (`blender`), the built add-on (build/blender_scripts),
numpy, matplotlib and OpenImageIO's Python module in this interpreter
(Debian: python3-matplotlib, python3-openimageio; /usr/bin/python3). Not part
of the test suite: it takes ~30 minutes with an empty cache (the Cycles
references are ~2/3 of that), ~10 minutes once the references are cached.

For each scene:
  * Cycles reference, cached under --cache keyed by sha256(.blend) + the
    settings below: max_bounces 0, denoising off, adaptive sampling off,
    Blackman-Harris filter of the scene's render.filter_size (copied into
    cycles.filter_width, which is what Cycles reads), same resolution as the
    other renders. It is rendered as two independent halves (seeds 1 and 2,
    N/2 samples each); the reference is their mean and its remaining noise
    is estimated as rms((a - b) / 2) (variance of the mean of two halves).
  * Deferred (ours) at several `scene.deferred_render.samples`, EEVEE at
    several `taa_render_samples` with shared/REFERENCE.md's fair settings
    (light_threshold 1e-4, soft shadows, high bit depth, no GTAO/SSR/bloom;
    shadow cube 1024 / cascade 2048: 4096 cube maps crash EEVEE 3.4 on
    llvmpipe with several lights), Cycles at low sample counts (seed 1000,
    independent of the reference's seeds).
  * All renders at the same size (--width, 320 px by default, through
    resolution_percentage), Combined pass only (the other passes are turned
    off for every engine), compositor and sequencer off.
  * Time: perf_counter around bpy.ops.render.render() inside Blender, after
    one warm-up render of the same engine in the same process (see
    blender_job.py); Blender start-up and file loading are excluded. The
    warm-up (cold) time is in the CSV too.
  * Memory: peak RSS of the Blender process during the render (VmHWM reset
    before each render); llvmpipe's "GPU" memory is process memory.
  * Error against the reference on Combined RGB: RMSE, relMSE, PSNR (peak =
    max of the reference) and mean(x)/mean(ref).

Outputs in --out: results.csv, report.md (tables), plots/<scene>.png
(log-log error against time), images/<scene>.png (reference / ours / EEVEE /
Cycles at a similar time, and error heat maps), renders/ (EXRs), logs/.
"""

import argparse
import csv
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
SAMPLES_DIR = os.path.join(REPO, "blend_samples")

try:
    import numpy as np  # noqa: F401
    import matplotlib  # noqa: F401
    import OpenImageIO  # noqa: F401
except ImportError:
    # The first python3 on PATH may be a build without Debian's packages.
    if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
            os.path.exists("/usr/bin/python3") and not os.environ.get("REPORT_REEXEC"):
        os.environ["REPORT_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3", os.path.abspath(__file__)] + sys.argv[1:])
    raise

sys.path.insert(0, HERE)
import metrics  # noqa: E402
import figures  # noqa: E402

ENGINES = {"ours": "DEFERRED_RENDER", "ours_rays": "DEFERRED_RENDER", "eevee": "BLENDER_EEVEE", "cycles": "CYCLES"}
LABEL = {"ours": "Deferred (ours)", "ours_rays": "Deferred, shadow rays", "eevee": "EEVEE", "cycles": "Cycles"}
# Engine settings per series beyond the scene's own (ours_rays: Shadows = Shadow Rays).
SERIES_SETTINGS = {"ours_rays": {"deferred_settings": {"shadow_method": "RAYS"}}}
OURS = ("ours", "ours_rays")

# Per-scene plan. Costs measured on this machine (2 cores, llvmpipe) at
# 320x180: Cycles ~0.1-0.2 s per sample (many_lights ~0.55 s: 1024 lights);
# ours ~0.05-0.4 s per sample; EEVEE ~2.5 s fixed + 0.2..12 s per sample
# (many_lights: ~12 s per sample). The reference sample counts keep the whole
# report near 30 minutes with an empty cache; EEVEE's axis stops where a point
# would cost more than ~1-2 minutes.
# unocc_spp: the shadow-free reference (cheaper: it only checks ours).
PLANS = {
    "showcase":    {"ref_spp": 1024, "unocc_spp": 512, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64], "ours_noshadow": [16, 64]},
    # box_room: its chrome ball's highlight (radiance ~200 over a few pixels)
    # is reached by the pixel filter's tail of the pixels around it, whose
    # values a path tracer and this film alike sample by chance: Cycles'
    # 1024-sample halves disagreed 3x on one of them. The 8192-sample
    # reference (385 s here) resolves them; Cycles at 256 is the issue's
    # comparison at equal samples.
    "box_room":    {"ref_spp": 8192, "unocc_spp": 512, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64, 256], "ours_noshadow": [16, 64]},
    # many_lights: its 1024 small lights already have use_shadow off; only the
    # moon (0.05 W/m2) casts shadow maps, so no extra shadow-free run.
    "many_lights": {"ref_spp": 256, "unocc_spp": 128, "ours": [1, 4, 16], "eevee": [1, 4],
                    "cycles": [1, 4, 16, 64], "ours_noshadow": []},
    "instancing":  {"ref_spp": 512, "unocc_spp": 256, "ours_rays": [1, 4, 16, 64], "ours": [1, 4, 16, 64], "eevee": [1, 4, 16],
                    "cycles": [1, 4, 16, 64], "ours_noshadow": [16, 64]},
    "analytic":    {"ref_spp": 1024, "unocc_spp": 1024, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64], "ours_noshadow": [4, 16, 64]},
    # hdri_studio: lit by an HDRI only (world map, importance sampling,
    # map-drawn occlusion directions); 256 samples show the convergence.
    "hdri_studio": {"ref_spp": 1024, "unocc_spp": 512, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64, 256], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64, 256], "ours_noshadow": [64]},
    # sky_sun: a Nishita sky and its sun disc (a sun lamp with shadow
    # cascades); emitters: emissive meshes only (a constant panel, a baked
    # Checker panel, 5000 small triangles); 256 samples show the convergence.
    "sky_sun":     {"ref_spp": 1024, "unocc_spp": 512, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64, 256], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64, 256], "ours_noshadow": [64]},
    # emitters: no shadow-free run (its lights are meshes, which have no
    # use_shadow switch: the run shadowed them anyway, mean/ref 1.18).
    "emitters":    {"ref_spp": 1024, "unocc_spp": 512, "ours_rays": [1, 4, 16, 64, 256], "ours": [1, 4, 16, 64, 256], "eevee": [1, 4, 16, 64],
                    "cycles": [1, 4, 16, 64, 256], "ours_noshadow": []},
    # transparency: stochastic alpha (leaf cut-out, panes, a Transparent mix)
    # converging with its partial shadows; 256 samples show the convergence.
    "transparency": {"ref_spp": 1024, "unocc_spp": 256, "ours": [1, 4, 16, 64, 256], "eevee": [1, 4, 16, 64],
                     "cycles": [1, 4, 16, 64, 256], "ours_noshadow": []},
}
DEFAULT_PLAN = {"ref_spp": 1024, "unocc_spp": 512, "ours": [1, 4, 16, 64], "eevee": [1, 4, 16],
                "cycles": [1, 4, 16, 64], "ours_noshadow": [16, 64]}
SAMPLE_SCENES = list(PLANS)

EEVEE_SETTINGS = {"light_threshold": 1e-4, "use_soft_shadows": True, "use_shadow_high_bitdepth": True,
                  "shadow_cube_size": "1024", "shadow_cascade_size": "2048",
                  "use_gtao": False, "use_ssr": False, "use_bloom": False}
REF_SEEDS = (1, 2)
CYCLES_SEED = 1000
JOB_VERSION = 2   # bump when the reference job changes in a way the cache key must see
JEMALLOC_CONF = "muzzy_decay_ms:-1,lg_extent_max_active_fit:20"  # native/src/cpu_rasteriser.h kJemallocConf


def log(msg):
    print(f"[report {time.strftime('%H:%M:%S')}] {msg}", flush=True)


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def blender_version(blender):
    out = subprocess.run([blender, "--version"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                         timeout=120).stdout.decode("utf-8", "replace")
    m = re.search(r"Blender (\S+)", out)
    return m.group(1) if m else "unknown"


def blender_env():
    """Our environment minus pyenv: Blender's embedded Python 3.11 finds its
    prefix through the python3.11 first on PATH, and a pyenv build there has
    no Debian numpy (the add-on then fails to import)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYENV") and k != "_PYENV_INSTALL_PREFIX"}
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep) if "pyenv" not in p)
    env.pop("PYTHONHOME", None)
    env.pop("PYTHONPATH", None)
    # Every engine's Blender with the jemalloc setting the README gives for
    # CPU renders (native/src/cpu_rasteriser.h): without it llvmpipe faults
    # its freed memory in again for every draw batch.
    env.setdefault("MALLOC_CONF", JEMALLOC_CONF)
    return env


def run_blender(args, blend, engine, job, log_path):
    """Run one Blender process for a job; returns its results dict."""
    os.makedirs(os.path.dirname(log_path), exist_ok=True)
    job_path = os.path.splitext(log_path)[0] + ".job.json"
    with open(job_path, "w") as f:
        json.dump(job, f, indent=1)
    cmd = [args.blender, "-b", "--factory-startup"]
    if engine == "DEFERRED_RENDER":
        cmd += ["--addons", "deferred_render"]
    cmd += [blend, "--python-exit-code", "1", "--python", os.path.join(HERE, "blender_job.py"), "--", job_path]
    env = blender_env()
    env["BLENDER_USER_SCRIPTS"] = os.path.join(args.build, "blender_scripts")
    if os.path.exists(job["results"]):
        os.remove(job["results"])
    t0 = time.perf_counter()
    with open(log_path, "w") as logf:
        proc = subprocess.run(cmd, stdout=logf, stderr=subprocess.STDOUT, env=env, timeout=args.timeout)
    wall = time.perf_counter() - t0
    results = None
    if os.path.exists(job["results"]):
        with open(job["results"]) as f:
            results = json.load(f)
    if proc.returncode != 0 or results is None:
        tail = open(log_path, errors="replace").read()[-2000:]
        if results is None or not results.get("renders"):
            raise RuntimeError(f"Blender failed ({engine} on {blend}, exit {proc.returncode}); "
                               f"log {log_path}:\n{tail}")
        log(f"  WARNING: Blender exited {proc.returncode} after {len(results['renders'])} renders "
            f"({engine}); keeping those. Log: {log_path}")
    results["wall_seconds"] = wall
    if engine == "DEFERRED_RENDER":
        attach_deferred_breakdown(results, log_path)
    return results


def attach_deferred_breakdown(results, log_path):
    """Our engine prints 'done in ... [total (upload, geometry, lighting ...)]'
    per render; keep the last one before each spec's report_job line."""
    last, per_spec = None, []
    with open(log_path, errors="replace") as f:
        for line in f:
            if "| done in " in line:
                last = line.split("| done in ", 1)[1].strip()
            elif line.startswith("report_job:") and "warm-up" not in line:
                per_spec.append(last)
    for entry, text in zip(results.get("renders", []), per_spec):
        entry["breakdown"] = text


def engine_provenance(build):
    """Which source the add-on in --build was built from: commit (+dirty)."""
    src = None
    try:
        with open(os.path.join(build, "CMakeCache.txt")) as f:
            for line in f:
                if line.startswith("CMAKE_HOME_DIRECTORY:"):
                    src = line.split("=", 1)[1].strip()
    except OSError:
        return "unknown source"
    if src and os.path.exists(os.path.join(src, "COMMIT")):
        with open(os.path.join(src, "COMMIT")) as f:
            return f"commit {f.read().strip()[:12]} (exported tree {src})"
    if src:
        try:
            head = subprocess.run(["git", "-C", src, "rev-parse", "HEAD"], stdout=subprocess.PIPE,
                                  stderr=subprocess.DEVNULL).stdout.decode().strip()
            dirty = subprocess.run(["git", "-C", src, "status", "--porcelain", "--untracked-files=no"],
                                   stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout.decode().strip()
            return f"commit {head[:12]}" + (" + uncommitted changes" if dirty else "") + f" ({src})"
        except OSError:
            pass
    return f"source {src}"


def quick_plan(plan):
    return {"ref_spp": 16, "unocc_spp": 16, "ours": [1, 4], "eevee": [1], "cycles": [1, 4], "ours_noshadow": [4]}


def scene_list(args):
    scenes = []
    for name in args.scenes:
        if name not in PLANS:
            raise SystemExit(f"unknown sample scene '{name}' (choose from {', '.join(PLANS)})")
        scenes.append((name, os.path.join(SAMPLES_DIR, name + ".blend"), dict(PLANS[name])))
    for path in args.blend:
        if not os.path.exists(path):
            raise SystemExit(f"no such file: {path}")
        name = os.path.splitext(os.path.basename(path))[0]
        plan = dict(PLANS.get(name, DEFAULT_PLAN)) if os.path.abspath(path).startswith(SAMPLES_DIR) \
            else dict(DEFAULT_PLAN)
        scenes.append((name, os.path.abspath(path), plan))
    if args.quick:
        scenes = [(n, b, quick_plan(p)) for n, b, p in scenes]
    return scenes


def reference(args, name, blend, plan, version, unoccluded=False):
    """Cached Cycles reference (two halves). unoccluded: no object blocks
    any shadow or BSDF ray (blender_job.disable_shadows), so nothing is in
    shadow (what the Deferred engine computes while it has no shadows)."""
    spp = args.ref_spp or plan["unocc_spp" if unoccluded else "ref_spp"]
    key_data = {"blend_sha256": sha256_file(blend), "spp": spp, "seeds": REF_SEEDS, "width": args.width,
                "blender": version, "job_version": JOB_VERSION, "unoccluded": bool(unoccluded)}
    key = hashlib.sha256(json.dumps(key_data, sort_keys=True).encode()).hexdigest()[:16]
    what = "unoccluded Cycles reference" if unoccluded else "Cycles reference"
    cdir = os.path.join(args.cache, f"{name}{'-unoccluded' if unoccluded else ''}-{key}")
    meta_path = os.path.join(cdir, "meta.json")
    if os.path.exists(meta_path):
        with open(meta_path) as f:
            meta = json.load(f)
        if all(os.path.exists(os.path.join(cdir, r)) for r in ("ref_a.exr", "ref_b.exr")):
            log(f"{name}: {what} from cache {cdir}")
            return cdir, meta
    os.makedirs(cdir, exist_ok=True)
    log(f"{name}: rendering the {what}, {spp} samples as 2 x {spp // 2} (seeds {REF_SEEDS}) ...")
    job = {"engine": "CYCLES", "target_width": args.width, "warmup": False, "index_pass": True,
           "no_shadows": bool(unoccluded),
           "renders": [{"samples": spp // 2, "seed": REF_SEEDS[0], "out": os.path.join(cdir, "ref_a.exr")},
                       {"samples": spp // 2, "seed": REF_SEEDS[1], "out": os.path.join(cdir, "ref_b.exr")}],
           "results": os.path.join(cdir, "results.json")}
    res = run_blender(args, blend, "CYCLES", job, os.path.join(cdir, "blender.log"))
    if len(res["renders"]) != 2:
        raise RuntimeError(f"{name}: reference incomplete")
    meta = {"key": key_data, "spp": spp, "results": res}
    with open(meta_path, "w") as f:
        json.dump(meta, f, indent=1)
    log(f"{name}: {what} done in {sum(r['seconds'] for r in res['renders']):.0f} s")
    return cdir, meta


def load_reference(cdir, meta):
    a, chans = metrics.read_rgb(os.path.join(cdir, "ref_a.exr"))
    b, _ = metrics.read_rgb(os.path.join(cdir, "ref_b.exr"))
    ref = (a + b) / 2.0
    noise = metrics.reference_noise(a, b, ref)
    index = None
    for cname in chans:
        if cname.endswith("IndexOB.X"):
            index = chans[cname]
    res = meta["results"]
    peak = float(ref.max())
    info = {"width": res["width"], "height": res["height"], "spp": meta["spp"],
            "seconds": sum(r["seconds"] for r in res["renders"]), "peak": peak,
            "noise_rmse": noise["rmse"], "noise_mse": noise["mse"], "noise_relmse": noise["relmse"],
            "noise_psnr": 10 * math.log10(peak ** 2 / noise["mse"]) if noise["mse"] > 0 else float("inf"),
            "index": index, "pass_index_names": res.get("pass_index_names") or {},
            "ref_peak_rss_mb": max(r["peak_rss_mb"] for r in res["renders"])}
    return ref, np.abs(a - b).mean(-1) / 2.0, info


# Extra job: ours with every light's use_shadow off, compared with the
# unoccluded reference only (isolates everything but shadows).
UNOCC_KEY = "ours_noshadow"
LABEL_NOSHADOW = "Deferred, shadows off"


def measure(args, name, blend, plan):
    runs = {}
    jobs = [(key, engine, plan.get(key, []), SERIES_SETTINGS.get(key, {})) for key, engine in ENGINES.items()]
    if not args.no_unoccluded and plan.get("ours_noshadow"):
        jobs.append((UNOCC_KEY, "DEFERRED_RENDER", plan["ours_noshadow"], {"no_shadows": True}))
    for key, engine, counts, extra in jobs:
        if (key if key in ENGINES else "ours") in args.skip or (key == "ours_rays" and "ours" in args.skip) \
                or not counts:
            continue
        label = LABEL.get(key, LABEL_NOSHADOW)
        rdir = os.path.join(args.out, "renders", name)
        job = {"engine": engine, "target_width": args.width, "warmup": True,
               "renders": [{"samples": n, "seed": CYCLES_SEED, "out": os.path.join(rdir, f"{key}_{n:04d}.exr")}
                           for n in counts],
               "results": os.path.join(rdir, f"{key}.json"), **extra}
        if engine == "BLENDER_EEVEE":
            job["eevee"] = EEVEE_SETTINGS
        log_path = os.path.join(args.out, "logs", f"{name}_{key}.log")
        stamp = {"blend_sha256": sha256_file(blend), "engine_build": args.provenance, "job": job}
        if args.resume and os.path.exists(job["results"]):
            with open(job["results"]) as f:
                old = json.load(f)
            if old.get("stamp") == stamp and len(old.get("renders", [])) == len(counts):
                for r in old["renders"]:
                    r["out"] = os.path.join(rdir, os.path.basename(r["out"]))
                if engine == "DEFERRED_RENDER" and os.path.exists(log_path):
                    attach_deferred_breakdown(old, log_path)
                log(f"{name}: {label} at {counts} samples: reused (--resume)")
                runs[key] = old
                continue
        log(f"{name}: {label} at {counts} samples ...")
        try:
            res = run_blender(args, blend, engine, job, log_path)
        except Exception as ex:   # one engine failing must not lose the rest of the report
            log(f"  {label} FAILED: {str(ex)[:400]}")
            runs[key] = {"failed": str(ex)[:2000], "renders": []}
            continue
        for r in res["renders"]:
            log(f"  {label} {r['samples']:>4} samples: {r['seconds']:8.3f} s, "
                f"peak RSS {r['peak_rss_mb']:.0f} MB")
        res["stamp"] = stamp
        with open(job["results"], "w") as f:
            json.dump(res, f, indent=1)
        runs[key] = res
    return runs


def load_measured(args, name):
    runs = {}
    for key in list(ENGINES) + [UNOCC_KEY]:
        path = os.path.join(args.out, "renders", name, f"{key}.json")
        if os.path.exists(path):
            with open(path) as f:
                res = json.load(f)
            for r in res.get("renders", []):   # the EXRs next to the JSON, wherever --out was then
                r["out"] = os.path.join(args.out, "renders", name, os.path.basename(r["out"]))
            log_path = os.path.join(args.out, "logs", f"{name}_{key}.log")
            if key in (*OURS, UNOCC_KEY) and os.path.exists(log_path):
                attach_deferred_breakdown(res, log_path)
            runs[key] = res
    return runs


def analyse(name, refs, runs):
    ref, ref_noise, info = load_reference(*refs["main"])
    info["scene"] = name
    peak = info["peak"]
    unocc = None
    if refs.get("unoccluded"):
        uref, unoise, uinfo = load_reference(*refs["unoccluded"])
        unocc = (uref, uinfo)
        info["unoccluded"] = uinfo
    rows, images = [], {"ref": ref, "ref_noise": ref_noise}
    if unocc is not None:
        images["ref_unoccluded"] = unocc[0]
        images["ref_unoccluded_noise"] = unoise
    for key, res in runs.items():
        if key == UNOCC_KEY:
            continue
        for r in res.get("renders", []):
            x, _ = metrics.read_rgb(r["out"])
            if x.shape != ref.shape:
                raise RuntimeError(f"{r['out']}: size {x.shape} differs from the reference {ref.shape}")
            e = metrics.errors(x, ref, peak)
            row = {"scene": name, "engine": key, "samples": r["samples"], "seconds": r["seconds"],
                   "cold_seconds": (res.get("cold") or {}).get("seconds"),
                   "peak_rss_mb": r["peak_rss_mb"], "rss_before_mb": r["rss_before_mb"],
                   "width": res["width"], "height": res["height"], **e,
                   "breakdown": r.get("breakdown", ""), "load": r.get("loadavg_1min_before")}
            if unocc is not None:
                eu = metrics.errors(x, unocc[0], unocc[1]["peak"])
                row.update({f"{k}_unocc": v for k, v in eu.items()})
            rows.append(row)
            images[(key, r["samples"])] = x
    info["noshadow"] = []
    if unocc is not None and runs.get(UNOCC_KEY):
        res = runs[UNOCC_KEY]
        for r in res.get("renders", []):
            x, _ = metrics.read_rgb(r["out"])
            eu = metrics.errors(x, unocc[0], unocc[1]["peak"])
            info["noshadow"].append({"scene": name, "engine": UNOCC_KEY, "samples": r["samples"],
                                     "seconds": r["seconds"], "peak_rss_mb": r["peak_rss_mb"],
                                     "breakdown": r.get("breakdown", ""),
                                     **{f"{k}_unocc": v for k, v in eu.items()}})
            images[(UNOCC_KEY, r["samples"])] = x
    if runs.get("ours", {}).get("deferred"):
        info["deferred_settings"] = runs["ours"]["deferred"]
    return rows, images, info


def curves(rows, info, metric="rmse"):
    out = {}
    for key in ENGINES:
        pts = [(r["samples"], r["seconds"], r[metric]) for r in rows if r["engine"] == key]
        if not pts:
            continue
        model = None
        if key == "cycles" and metric == "rmse":
            model = metrics.CyclesModel([p[0] for p in pts], [p[1] for p in pts],
                                        [p[2] ** 2 for p in pts], info["noise_mse"])
        out[key] = metrics.Curve(pts, model)
    return out


def comparisons(rows, info):
    """For each of our sample counts: the others' error at our time and the
    others' time to our error (RMSE), as ratios other/ours."""
    cs = curves(rows, info)
    out = []
    for r in sorted((r for r in rows if r["engine"] in OURS), key=lambda r: (r["engine"], r["samples"])):
        c = {"scene": info["scene"], "engine": r["engine"], "samples": r["samples"], "seconds": r["seconds"],
             "rmse": r["rmse"]}
        for key in ("eevee", "cycles"):
            if key not in cs:
                continue
            e, ek = cs[key].error_at_time(r["seconds"])
            t, tk = cs[key].time_for_error(r["rmse"])
            c[f"{key}_err"], c[f"{key}_err_kind"] = e, ek
            c[f"{key}_time"], c[f"{key}_time_kind"] = t, tk
        out.append(c)
    return out


# ---------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------

CSV_FIELDS = ["scene", "engine", "samples", "seconds", "cold_seconds", "peak_rss_mb", "rss_before_mb",
              "width", "height", "rmse", "relmse", "psnr", "mean_ratio", "mse",
              "rmse_unocc", "relmse_unocc", "mean_ratio_unocc", "load", "breakdown"]


def fmt(v, digits=3):
    if v is None:
        return "–"
    if isinstance(v, float):
        if math.isinf(v):
            return "inf"
        if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5):
            return f"{v:.{digits - 1}e}"
        return f"{v:.{digits}g}" if abs(v) < 1 else f"{v:.{max(digits - len(str(int(abs(v)))), 0) + 1}f}"
    return str(v)


def ratio_text(other, kind, ours, what):
    """other/ours with the interpolation kind ('=' measured, '~' Cycles model,
    bounds otherwise)."""
    if kind == "slower":
        return "slower"
    if kind == "never":
        return "never"
    if other is None:
        return "–"
    ratio = other / ours if ours > 0 else float("inf")
    prefix = {"=": "", "~": "~", ">=": "≤" if what == "err" else "", "<=": "≤", ">": ">"}.get(kind, "")
    return f"{prefix}{ratio:.2g}×"


def write_outputs(args, all_rows, infos, comps, objects):
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in all_rows:
            w.writerow(r)
    with open(os.path.join(args.out, "reference.csv"), "w", newline="") as f:
        fields = ["scene", "width", "height", "spp", "seconds", "peak", "noise_rmse", "noise_relmse",
                  "noise_psnr", "ref_peak_rss_mb"]
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for i in infos:
            w.writerow(i)
    md = markdown(all_rows, infos, comps, args.header)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(md)
        f.write(objects_markdown(objects))
    return md


def objects_markdown(objects):
    """Per-object energy: mean Combined over interior pixels of each object
    (reference IndexOB), engine / reference, at each engine's most samples."""
    if not objects:
        return ""
    L = ["", "Per object (IndexOB of the reference, interior pixels): mean Combined of each engine at its "
         "most samples over the reference's (sum of RGB; per channel in objects/<scene>.csv). "
         "`ours/unocc`: ours with shadows off against the unoccluded reference.", "",
         "| scene | pass index | objects | pixels | ours/ref | ours rays/ref | EEVEE/ref | Cycles/ref | ours/unocc |",
         "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    unocc = {(o["scene"], o["pass_index"]): o for o in objects if o["against"] == "unoccluded"}
    for o in objects:
        if o["against"] == "unoccluded":
            continue
        u = unocc.get((o["scene"], o["pass_index"]), {})
        u = {"ours_ratio": u.get(f"{UNOCC_KEY}_ratio", u.get("ours_ratio"))} if u else {}
        L.append(f"| {o['scene']} | {o['pass_index']} | {o['objects'][:48]} | {o['pixels']} | "
                 + " | ".join(f"{o[k]:.3f}" if k in o else "–" for k in ("ours_ratio", "ours_rays_ratio", "eevee_ratio", "cycles_ratio"))
                 + (f" | {u['ours_ratio']:.3f} |" if u.get("ours_ratio") is not None else " | – |"))
    L.append("")
    return "\n".join(L)


def markdown(all_rows, infos, comps, header=""):
    L = [header, ""] if header else []
    L.append("Reference: Cycles, max_bounces 0, no denoising, N samples as two halves (seeds 1, 2); "
             "noise = rms((a−b)/2), the reference's own remaining error. PSNR peak = max of the reference.")
    L.append("")
    L.append("| scene | size | ref samples | ref time s | noise RMSE | noise relMSE | noise PSNR dB |")
    L.append("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
    for i in infos:
        L.append(f"| {i['scene']} | {i['width']}×{i['height']} | {i['spp']} | {i['seconds']:.0f} | "
                 f"{fmt(i['noise_rmse'])} | {fmt(i['noise_relmse'])} | {i['noise_psnr']:.1f} |")
    L.append("")
    ds = next((i["deferred_settings"] for i in infos if i.get("deferred_settings")), None)
    loads = [r["load"] for r in all_rows if r.get("load") is not None]
    L.append("Time: best of 3 (renders under 2 s) or single in-Blender `bpy.ops.render.render()` after one warm-up render "
             "(start-up excluded). Memory: peak RSS of the Blender process during the render. "
             "mean/ref: mean Combined over the reference's (energy)."
             + (" Deferred settings: " + ", ".join(f"{k} {v}" for k, v in sorted(ds.items())
                                                    if k != "samples") + "." if ds else "")
             + (f" Highest 1-min load average before a render: {max(loads):.1f} (the render's own "
                "2 threads count; much above 2 means other work shared the cores)." if loads else ""))
    L.append("")
    L.append("| scene | engine | samples | time s | peak RSS MB | RMSE | relMSE | PSNR dB | mean/ref |")
    L.append("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in all_rows:
        L.append(f"| {r['scene']} | {LABEL[r['engine']]} | {r['samples']} | {r['seconds']:.3f} | "
                 f"{r['peak_rss_mb']:.0f} | {fmt(r['rmse'])} | {fmt(r['relmse'])} | {r['psnr']:.1f} | "
                 f"{r['mean_ratio']:.3f} |")
    L.append("")
    L.append("Equal time: the other engine's RMSE at our render time, over ours (>1: ours is better). "
             "Equal error: the other engine's time to reach our RMSE, over ours (>1: ours is faster). "
             "Log-log interpolation between measured points; `~` = Cycles model MSE = noise_ref + b/n, "
             "time = t0 + k·n (outside the measured range); `≤`/`>` = bound from the measured range; "
             "`slower` = the engine's fastest render is slower than ours; "
             "`never` = below what Cycles can reach against this reference.")
    L.append("")
    L.append("| scene | ours | ours samples | ours time s | ours RMSE | EEVEE err ratio @ equal time | "
             "Cycles err ratio @ equal time | EEVEE time ratio @ equal error | Cycles time ratio @ equal error |")
    L.append("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for c in comps:
        cells = []
        for key in ("eevee", "cycles"):
            cells.append(ratio_text(c.get(f"{key}_err"), c.get(f"{key}_err_kind"), c["rmse"], "err")
                         if f"{key}_err_kind" in c else "–")
        for key in ("eevee", "cycles"):
            cells.append(ratio_text(c.get(f"{key}_time"), c.get(f"{key}_time_kind"), c["seconds"], "time")
                         if f"{key}_time_kind" in c else "–")
        L.append(f"| {c['scene']} | {'rays' if c.get('engine') == 'ours_rays' else 'maps'} | {c['samples']} | "
                 f"{c['seconds']:.3f} | {fmt(c['rmse'])} | " + " | ".join(cells) + " |")
    L.append("")
    unocc = [i for i in infos if "unoccluded" in i]
    if unocc:
        L.append("Shadows taken out: ours with every light's use_shadow off against the **unoccluded** "
                 "Cycles reference (every object's visible_shadow/diffuse/glossy/transmission and every "
                 "light's cast_shadow off, so no ray but the camera's hits geometry). Everything but "
                 "shadows: light and BSDF formulas, world light, anti-aliasing, soft light. Where ours "
                 "converges, the RMSE reaches the noise column. (many_lights: ours with its shadows.)")
        L.append("")
        L.append("| scene | ref samples | noise RMSE | noise relMSE | ours samples | time s | RMSE | relMSE | "
                 "mean/ref |")
        L.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for i in unocc:
            u = i["unoccluded"]
            rs = i.get("noshadow") or [r for r in all_rows if r["scene"] == i["scene"] and r["engine"] == "ours"]
            for r in sorted(rs, key=lambda r: r["samples"]):
                L.append(f"| {i['scene']} | {u['spp']} | {fmt(u['noise_rmse'])} | {fmt(u['noise_relmse'])} | "
                         f"{r['samples']} | {r['seconds']:.3f} | {fmt(r['rmse_unocc'])} | "
                         f"{fmt(r['relmse_unocc'])} | {r['mean_ratio_unocc']:.3f} |")
        L.append("")
    splits = [r for r in all_rows if r["engine"] in OURS and r.get("breakdown")]
    if splits:
        L.append("Where our time goes (the engine's own split, ms, at the most samples):")
        L.append("")
        L.append("| scene | shadows | samples | split |")
        L.append("| --- | --- | ---: | --- |")
        for i in infos:
            for key in OURS:
                rs = [r for r in splits if r["scene"] == i["scene"] and r["engine"] == key]
                if rs:
                    r = max(rs, key=lambda r: r["samples"])
                    L.append(f"| {i['scene']} | {'rays' if key == 'ours_rays' else 'maps'} | {r['samples']} | "
                             f"{r['breakdown']} |")
        L.append("")
    return "\n".join(L)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("blend", nargs="*", help="extra .blend files to report on")
    p.add_argument("--scenes", nargs="*", default=None,
                   help=f"sample scenes (default: all of {', '.join(SAMPLE_SCENES)}; "
                        "none when only .blend files are given)")
    p.add_argument("--out", default=os.path.join(HERE, "out"))
    p.add_argument("--cache", default=os.path.join(HERE, "cache"), help="Cycles reference cache")
    p.add_argument("--build", default=os.path.join(REPO, "build"), help="build dir with blender_scripts/")
    p.add_argument("--blender", default=shutil.which("blender") or "blender")
    p.add_argument("--width", type=int, default=320, help="render width (via resolution_percentage)")
    p.add_argument("--ref-spp", type=int, default=None, help="override every reference's sample count")
    p.add_argument("--skip", nargs="*", default=[], choices=list(ENGINES), help="engines to leave out")
    p.add_argument("--no-unoccluded", action="store_true",
                   help="skip the second, shadow-free Cycles reference (no object blocks any light)")
    p.add_argument("--quick", action="store_true",
                   help="smoke test: 16-sample references, 1 and 4 samples (EEVEE 1); numbers are not meaningful")
    p.add_argument("--resume", action="store_true",
                   help="reuse an engine's renders in --out when the .blend, the engine build and the job "
                        "are the same (finish an interrupted report)")
    p.add_argument("--analyse-only", action="store_true",
                   help="do not render: rebuild tables and figures from --out/renders and the cache")
    p.add_argument("--timeout", type=float, default=3600.0, help="seconds per Blender process")
    args = p.parse_args()
    if args.scenes is None:
        args.scenes = [] if args.blend else list(SAMPLE_SCENES)
    args.out = os.path.abspath(args.out)
    args.cache = os.path.abspath(args.cache)
    if not os.path.isdir(os.path.join(args.build, "blender_scripts", "addons", "deferred_render")):
        raise SystemExit(f"no add-on in {args.build}/blender_scripts: build first "
                         "(cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build -j2)")
    version = blender_version(args.blender)
    provenance = engine_provenance(args.build)
    args.provenance = provenance
    args.header = (f"Measured {time.strftime('%Y-%m-%d')} on {os.cpu_count()} cores, Mesa llvmpipe, Blender "
                   f"{version}; Deferred engine built from {provenance}.")
    log(f"Blender {version}; engine {provenance}; width {args.width}; out {args.out}; cache {args.cache}")
    t_start = time.perf_counter()
    all_rows, infos, comps, objects = [], [], [], []
    for name, blend, plan in scene_list(args):
        t_scene = time.perf_counter()
        refs = {"main": reference(args, name, blend, plan, version)}
        if not args.no_unoccluded:
            refs["unoccluded"] = reference(args, name, blend, plan, version, unoccluded=True)
        runs = load_measured(args, name) if args.analyse_only else measure(args, name, blend, plan)
        rows, images, info = analyse(name, refs, runs)
        log(f"{name}: reference noise RMSE {info['noise_rmse']:.3g} (relMSE {info['noise_relmse']:.3g}); "
            f"scene took {time.perf_counter() - t_scene:.0f} s")
        for r in rows:
            log(f"  {LABEL[r['engine']]:>16} {r['samples']:>4}: {r['seconds']:8.3f} s  RMSE {r['rmse']:.4g}  "
                f"relMSE {r['relmse']:.4g}  PSNR {r['psnr']:.1f}  mean/ref {r['mean_ratio']:.3f}")
        c = comparisons(rows, info)
        all_rows += rows
        infos.append(info)
        comps += c
        figures.error_plot(os.path.join(args.out, "plots", f"{name}.png"), name, rows, info, LABEL)
        figures.side_by_side(os.path.join(args.out, "images", f"{name}.png"), name, rows, images, info, LABEL)
        if info["index"] is not None:
            objects += figures.per_object(os.path.join(args.out, "objects", f"{name}.csv"), name, rows,
                                          images, info, images["ref"])
        if "unoccluded" in info:
            urows, ukey = (info["noshadow"], UNOCC_KEY) if info.get("noshadow") else (rows, "ours")
            labels = dict(LABEL, **{UNOCC_KEY: LABEL_NOSHADOW})
            figures.unoccluded_view(os.path.join(args.out, "images", f"{name}_unoccluded.png"), name, urows,
                                    images, info, labels, key=ukey)
            uinfo = info["unoccluded"]
            if uinfo["index"] is not None:
                objects += figures.per_object(os.path.join(args.out, "objects", f"{name}_unoccluded.csv"),
                                              name, urows, images, uinfo, images["ref_unoccluded"],
                                              engines=(ukey,), label="unoccluded")
        # tables after every scene, so an interrupted run still leaves a report
        write_outputs(args, all_rows, infos, comps, objects)
    if infos:
        figures.overview(os.path.join(args.out, "plots", "all_scenes.png"), all_rows, infos, LABEL)
    md = write_outputs(args, all_rows, infos, comps, objects)
    print(md)
    log(f"done in {time.perf_counter() - t_start:.0f} s; {os.path.join(args.out, 'report.md')}")


if __name__ == "__main__":
    main()
