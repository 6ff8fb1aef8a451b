#!/usr/bin/env python3
"""Scale-out on a real Slurm cluster: a single-node cluster started by the test
(scripts/cluster/local_slurm.sh: slurmctld, slurmd and munged with a
generated configuration and key, four GPUs declared as GRES so that Slurm
sets CUDA_VISIBLE_DEVICES per task as on a GPU node) renders a 12-frame
animation of the turntable sample as a job array of 4 tasks.

Checks:
  * one task is killed (SIGKILL to its Blender) while it renders a frame:
    the summary names the task as failed and the frames it left, none of
    them has a final file,
    every final file there is complete (a full-size EXR);
  * resubmitting the same command submits only the task that misses frames
    and completes the animation;
  * every frame equals the same frame rendered directly with
    `blender -b -a`, within the bound derived at SAME_FRAME below (and a
    neighbouring frame does not);
  * the tasks saw different CUDA_VISIBLE_DEVICES (one GPU each) and the
    engine recorded the device it rendered on;
  * render_gpus.sh (one process per GPU, no scheduler) renders frames 1-4
    with CUDA_VISIBLE_DEVICES 0 and 1, equal to the direct frames; the engine
    notes that the variable has no effect without NVIDIA.

    python3 tests/cluster/test_slurm_farm.py --build build

Exit status 77 (CTest's skip) where Slurm or munge is not installed or the
test is not root (local_slurm.sh needs root).
"""

import argparse
import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
CLUSTER = os.path.join(REPO, "scripts", "cluster")
FRAMES = (1, 12)
PER_TASK = 3
# Bound for a farm frame against the direct render of the same frame. The
# renderer's sample sequences depend on the film sample only (not on time or
# process), but its input does not repeat bit for bit: Blender 3.4 sums the
# split normals of smooth meshes on several threads, so two Blender processes
# give the turntable's spheres normals that differ in the last bits (checked:
# the md5 of SphereA's loop normals changes from run to run). Two direct
# renders of one frame differ by up to 3e-5 of the value in at most ~20 of
# the 57 600 pixels, in Normal and the shading; a frame rendered from other
# inputs (another frame, another sample count) differs by O(1) in most
# pixels. The bound leaves 30x room over the first and is far under the
# second: relative difference <= 1e-3 (absolute below 1e-3), in < 1 % of pixels.
SAME_FRAME_RELATIVE = 1e-3
SAME_FRAME_PIXEL_FRACTION = 0.01


class Failure(Exception):
    pass


def check(condition, message):
    print(("ok   " if condition else "FAIL ") + message, flush=True)
    if not condition:
        raise Failure(message)


def run(cmd, env, check_rc=True, **kw):
    print("$ " + " ".join(cmd), flush=True)
    p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw)
    if check_rc and p.returncode != 0:
        print(p.stdout)
        raise Failure(f"{cmd[0:3]} exited {p.returncode}")
    return p


def wait_for(predicate, timeout, what):
    """Polls a condition (the test's only waiting; it never sleeps blindly)."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.02)
    raise Failure(f"timed out after {timeout} s waiting for {what}")


def read_exr(path):
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise Failure(f"cannot open {path}: {oiio.geterror()}")
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    if pixels is None:
        raise Failure(f"cannot read {path}")
    return np.asarray(pixels), (spec.width, spec.height, tuple(spec.channelnames))


def same_frame_difference(a, b):
    """(largest |a-b| / max(|b|, 1) over every channel, fraction of pixels
    where any channel differs)."""
    d = np.abs(a - b)
    rel = float(np.max(d / np.maximum(np.abs(b), 1.0)))
    return rel, float(np.mean(np.any(d > 0, axis=-1)))


def make_test_blend(tmp, env):
    """The turntable at 8 samples: a few seconds a frame on llvmpipe."""
    path = os.path.join(tmp, "turntable.blend")
    expr = ("import bpy; s = bpy.context.scene; s.deferred_render.samples = 8; "
            f"bpy.ops.wm.save_as_mainfile(filepath={path!r})")
    run(["blender", "-b", "--factory-startup", os.path.join(REPO, "blend_samples", "turntable.blend"),
         "--addons", "deferred_render", "--python-exit-code", "1", "--python-expr", expr], env)
    return path


def task_logs(out):
    return sorted(glob.glob(os.path.join(out, ".deferred_farm", "logs", "slurm-*_*.out")))


def blender_pid_rendering(out, frame):
    """The pid of the task whose log says it started `frame` (and not yet
    finished it): render_frames.py prints both lines, and render_task.sh
    execs Blender, so the task's pid is Blender's."""
    for log in task_logs(out):
        text = open(log, errors="replace").read()
        if f"render_frames: frame {frame} started" in text and f"render_frames: frame {frame} done" not in text:
            for line in text.splitlines():
                if line.startswith("render_frames: task ") and " pid " in line:
                    return int(line.split(" pid ")[1].split(",")[0])
    return None


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=os.path.join(REPO, "build"))
    args = parser.parse_args()
    for tool in ("slurmctld", "slurmd", "munged", "sbatch"):
        if shutil.which(tool) is None and not os.path.exists(f"/usr/sbin/{tool}"):
            print(f"SKIP: {tool} is not installed (Debian: slurmctld slurmd slurm-client munge)")
            return 77

    if os.geteuid() != 0:
        print("SKIP: local_slurm.sh runs the daemons as root (mknod for the GPU device nodes)")
        return 77

    tmp = tempfile.mkdtemp(prefix="deferred-farm-")
    env = dict(os.environ)
    env["BLENDER_USER_SCRIPTS"] = os.path.join(os.path.abspath(args.build), "blender_scripts")
    env["LOCAL_SLURM_DIR"] = os.path.join(tmp, "slurm")
    env["DEFERRED_FARM_STATE"] = os.path.join(tmp, "jobs")
    env["SLURM_CONF"] = os.path.join(env["LOCAL_SLURM_DIR"], "slurm.conf")
    env["SLURM_RENDER_POLL_S"] = "0.5"
    env.pop("CUDA_VISIBLE_DEVICES", None)
    local_slurm = os.path.join(CLUSTER, "local_slurm.sh")
    slurm_render = os.path.join(CLUSTER, "slurm_render.sh")
    first, last = FRAMES
    try:
        blend = make_test_blend(tmp, env)
        t0 = time.time()
        run(["bash", local_slurm, "start"], env)
        print(f"cluster up in {time.time() - t0:.1f} s", flush=True)

        # -- the job array, one task killed mid-frame ---------------------
        out = os.path.join(tmp, "frames")
        submit = ["bash", slurm_render, blend, out, str(first), str(last), str(PER_TASK)]
        job = run(submit, env).stdout.strip().splitlines()[-1]
        check(job.isdigit(), f"sbatch job id printed: {job}")
        victim_frame = first + PER_TASK + 1  # the second frame of task 1
        pid = wait_for(lambda: blender_pid_rendering(out, victim_frame), 300,
                       f"task 1 to start frame {victim_frame}")
        os.kill(pid, signal.SIGKILL)
        print(f"killed Blender pid {pid} while it rendered frame {victim_frame}", flush=True)
        waited = run(["bash", slurm_render, "--wait", job], env, check_rc=False)
        print(waited.stdout)
        check(waited.returncode == 1, "--wait exits 1 when frames are missing")
        summary = json.load(open(os.path.join(out, ".deferred_farm", f"summary-{job}.json")))
        missing = summary["missing"]
        check(victim_frame in missing, f"the killed frame {victim_frame} is reported missing ({missing})")
        check(set(missing) <= set(range(first + PER_TASK, first + 2 * PER_TASK)),
              f"only the killed task's frames are missing ({missing})")
        check("resubmit the missing frames with" in waited.stdout, "--wait prints how to resubmit")
        check("task 1: FAILED" in waited.stdout, "--wait names the killed task as failed")
        for frame in missing:
            check(not os.path.exists(os.path.join(out, f"{frame:04d}.exr")),
                  f"no final file for unfinished frame {frame}")
        shapes = set()
        for path in sorted(glob.glob(os.path.join(out, "*.exr"))):
            _, (width, height, channels) = read_exr(path)  # a truncated EXR fails to read
            shapes.add((width, height, len(channels)))
        check(len(shapes) == 1, f"every final file is a complete EXR of one size and channel count ({shapes})")

        # -- resubmission completes it ------------------------------------
        job2 = run(submit, env).stdout.strip().splitlines()[-1]
        check(job2.isdigit() and job2 != job, f"resubmitted as job {job2}")
        array = run(["scontrol", "show", "job", job2], env).stdout
        check("ArrayTaskId=1 " in array or "ArrayTaskId=1\n" in array,
              "the resubmission runs only task 1")
        waited = run(["bash", slurm_render, "--wait", job2], env, check_rc=False)
        print(waited.stdout)
        check(waited.returncode == 0, "--wait exits 0: every frame exists")
        check("every frame exists" in waited.stdout, "the summary says every frame exists")
        again = run(submit, env)
        check("nothing to submit" in again.stdout, "a third submission has nothing to do")
        leftovers = glob.glob(os.path.join(out, ".partial", "*", "*"))
        print(f"partial files left by the killed attempt: {leftovers}")
        records = [json.load(open(p)) for p in glob.glob(os.path.join(out, ".deferred_farm", "[0-9]*.json"))]
        check(len(records) == last - first + 1, "a record per frame")
        visible = {r["task"]: r["cuda_visible_devices"] for r in records}
        check(all(v is not None for v in visible.values()), f"Slurm set CUDA_VISIBLE_DEVICES per task {visible}")
        first_job_tasks = {t: v for t, v in visible.items() if t.startswith(f"slurm-{job}_")}
        check(len(set(first_job_tasks.values())) == len(first_job_tasks) >= 3,
              f"concurrent tasks of one array got different GPUs {first_job_tasks}")
        check(all(r["gpu"] not in ("", "?") for r in records), "each record names the GPU")

        # -- equal to the direct render -----------------------------------
        direct = os.path.join(tmp, "direct")
        run(["blender", "-b", "--factory-startup", blend, "--addons", "deferred_render", "-E", "DEFERRED_RENDER",
             "-o", os.path.join(direct, "####"), "-s", str(first), "-e", str(last), "-a"], env)
        worst = (0.0, 0.0)
        for frame in range(first, last + 1):
            a, _ = read_exr(os.path.join(out, f"{frame:04d}.exr"))
            b, _ = read_exr(os.path.join(direct, f"{frame:04d}.exr"))
            worst = max(worst, same_frame_difference(a, b))
        check(worst[0] <= SAME_FRAME_RELATIVE and worst[1] < SAME_FRAME_PIXEL_FRACTION,
              f"every farm frame equals the direct frame (worst relative difference {worst[0]:.2g}, "
              f"{100 * worst[1]:.3f} % of pixels differ)")
        a, _ = read_exr(os.path.join(out, f"{first:04d}.exr"))
        b, _ = read_exr(os.path.join(direct, f"{first + 1:04d}.exr"))
        other = same_frame_difference(a, b)
        check(other[0] > SAME_FRAME_RELATIVE and other[1] > SAME_FRAME_PIXEL_FRACTION,
              f"the comparison tells frames apart (frame {first} vs {first + 1}: {other[0]:.2g}, "
              f"{100 * other[1]:.1f} % of pixels)")

        # -- one process per GPU, no scheduler ------------------------------
        local = os.path.join(tmp, "local")
        p = run(["bash", os.path.join(CLUSTER, "render_gpus.sh"), blend, local, "1", "4", "0,1"], env,
                check_rc=False)
        print(p.stdout)
        check(p.returncode == 0, "render_gpus.sh renders every frame")
        records = [json.load(open(p)) for p in glob.glob(os.path.join(local, ".deferred_farm", "[0-9]*.json"))]
        check(sorted(r["cuda_visible_devices"] for r in records) == ["0", "0", "1", "1"],
              "two processes, one per GPU, two frames each")
        check(all("has no effect here" in r["device_note"] for r in records),
              "without NVIDIA the engine notes that CUDA_VISIBLE_DEVICES has no effect")
        for frame in range(1, 5):
            a, _ = read_exr(os.path.join(local, f"{frame:04d}.exr"))
            b, _ = read_exr(os.path.join(direct, f"{frame:04d}.exr"))
            rel, frac = same_frame_difference(a, b)
            check(rel <= SAME_FRAME_RELATIVE and frac < SAME_FRAME_PIXEL_FRACTION,
                  f"render_gpus.sh frame {frame} equals the direct frame ({rel:.2g}, {100 * frac:.3f} % of pixels)")
    except Failure as e:
        print(f"FAILED: {e}")
        for log in task_logs(os.path.join(tmp, "frames")):
            print(f"--- {log}\n" + open(log, errors="replace").read()[-3000:])
        return 1
    finally:
        subprocess.run(["bash", local_slurm, "stop"], env=env)
        if os.environ.get("KEEP_FARM_TEST") != "1":
            shutil.rmtree(tmp, ignore_errors=True)
    print("test_slurm_farm: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
