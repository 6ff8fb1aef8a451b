"""Renders a list of frames of the open .blend, resumably: the Blender side of
the farm scripts (slurm_render.sh, render_gpus.sh).

    blender -b FILE.blend -E DEFERRED_RENDER --python-exit-code 1 \
        --python scripts/cluster/render_frames.py -- --output //frames/#### --frames 1-12 [--task NAME]

Per frame, in order:
  * the final name is Blender's: ``--output`` is what ``-o`` takes (``//``
    relative to the .blend, ``#`` the frame number, the extension of the
    scene's file format added as Blender adds it);
  * a frame whose final file exists is skipped: a resubmitted task renders
    only what is missing;
  * the frame is rendered with Blender's own writer into a private folder
    beside the output (``.partial/<task>/``) and then renamed onto the final
    name, an atomic step on one filesystem: a task killed mid-frame or
    mid-write leaves at most a file in ``.partial``, never a final name over
    a truncated file;
  * a frame whose render reported an error (the engine writes an empty image
    then) is not renamed; the task stops with exit code 1;
  * a record ``.deferred_farm/<frame>.json`` (host, GPU, seconds, task,
    CUDA_VISIBLE_DEVICES, when) is written the same way just before the
    rename; farm_summary.py counts a frame done when its record and the file
    it names both exist.
"""

import argparse
import json
import os
import shutil
import socket
import sys
import time

import bpy

RECORD_DIR = ".deferred_farm"
PARTIAL_DIR = ".partial"


def parse_frames(text):
    """'1-12', '1,3,5-7' -> sorted unique frame numbers."""
    frames = set()
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        if "-" in part[1:]:
            cut = part.index("-", 1)
            first, last = int(part[:cut]), int(part[cut + 1:])
            if last < first:
                raise ValueError(f"frame range '{part}' runs backwards")
            frames.update(range(first, last + 1))
        else:
            frames.add(int(part))
    if not frames:
        raise ValueError(f"no frames in '{text}'")
    return sorted(frames)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_frames.py")
    parser.add_argument("--output", required=True, help="output path as Blender's -o takes it")
    parser.add_argument("--frames", required=True, help="e.g. 1-12 or 1,4,7-9")
    parser.add_argument("--task", default=None, help="name of this task in records and .partial")
    return parser.parse_args(argv)


def task_name(explicit):
    if explicit:
        return explicit
    job = os.environ.get("SLURM_ARRAY_JOB_ID") or os.environ.get("SLURM_JOB_ID")
    index = os.environ.get("SLURM_ARRAY_TASK_ID")
    if job:
        return f"slurm-{job}" + (f"_{index}" if index is not None else "")
    return f"{socket.gethostname()}-{os.getpid()}"


def write_json_atomically(path, data):
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def engine_module():
    try:
        from deferred_render.engine import final
    except ImportError:
        return None
    return final


def render_errors(final):
    """Errors the engine reported during the last render (it reports rather
    than raises, so that Blender never crashes)."""
    return [text for level, text in final.last_messages if level == 'ERROR'] if final else []


def main():
    args = parse_args()
    scene = bpy.context.scene
    render = scene.render
    task = task_name(args.task)
    frames = parse_frames(args.frames)
    render.filepath = args.output
    render.use_overwrite = True
    render.use_placeholder = False
    finals = {frame: bpy.path.abspath(render.frame_path(frame=frame)) for frame in frames}
    out_dir = os.path.dirname(finals[frames[0]])
    records = os.path.join(out_dir, RECORD_DIR)
    partial = os.path.join(out_dir, PARTIAL_DIR, task)
    os.makedirs(records, exist_ok=True)
    os.makedirs(partial, exist_ok=True)
    # Blender writes the frame under the same base name, in the private folder.
    pattern = os.path.join(partial, os.path.basename(bpy.path.abspath(args.output)) or "####")

    print(f"render_frames: task {task} pid {os.getpid()}, {len(frames)} frame(s) "
          f"{frames[0]}..{frames[-1]} -> {out_dir}", flush=True)
    rendered = skipped = 0
    for frame in frames:
        final_path = finals[frame]
        if os.path.isfile(final_path):
            skipped += 1
            continue
        # What `blender -f FRAME` does: an animation render of one frame,
        # which names the file by the frame (a still would keep the #s).
        scene.frame_start = scene.frame_end = frame
        render.filepath = pattern
        written = bpy.path.abspath(render.frame_path(frame=frame))
        if os.path.exists(written):
            os.remove(written)  # left by a killed attempt of this task
        print(f"render_frames: frame {frame} started", flush=True)
        final = engine_module()
        if final is not None:
            final.last_messages.clear()  # a bounded deque: this frame's reports only
        t0 = time.time()
        try:
            bpy.ops.render.render(animation=True)
            errors = []
        except RuntimeError as ex:  # Blender refused the render (no camera, ...)
            errors = [str(ex)]
        seconds = time.time() - t0
        render.filepath = args.output
        errors += render_errors(final)
        if errors or not os.path.isfile(written):
            reason = "; ".join(errors) if errors else f"Blender wrote no file at {written}"
            print(f"render_frames: frame {frame} FAILED: {reason}", file=sys.stderr, flush=True)
            raise SystemExit(1)
        # The record first, then the frame: a record whose file is missing is
        # an unfinished frame (farm_summary.py), never the other way round.
        device = dict(final.last_device) if final is not None else {}
        write_json_atomically(os.path.join(records, f"{frame}.json"), {
            "frame": frame,
            "file": os.path.basename(final_path),
            "seconds": round(seconds, 3),
            "finished": time.time(),
            "host": socket.gethostname(),
            "gpu": device.get("gpu", "?"),
            "device": device.get("display", ""),
            "device_note": device.get("note", ""),
            "task": task,
            "cuda_visible_devices": os.environ.get("CUDA_VISIBLE_DEVICES"),
        })
        os.replace(written, final_path)
        rendered += 1
        print(f"render_frames: frame {frame} done in {seconds:.2f} s on {device.get('gpu', '?')}", flush=True)
    shutil.rmtree(partial, ignore_errors=True)
    try:
        os.rmdir(os.path.dirname(partial))  # the last task out removes .partial
    except OSError:
        pass
    print(f"render_frames: task {task} rendered {rendered}, skipped {skipped} already on disk", flush=True)


main()
