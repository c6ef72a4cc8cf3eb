#!/usr/bin/env python3
"""Speed against error, vkpt and Blender Cycles side by side on one glTF
scene: each render a whole separate process, its relMSE against one
reference (`vkpt compare`), and the time each series needs to reach a
relMSE threshold. A benchmark, never run by CI.

    cargo build --release
    python3 benches/cycles_speed_error.py SCENE.gltf --reference REF.exr
        [--spp 4,16,64,256] [--width 128] [--height 128]
        [--vkpt "power=--light-sampler power" --vkpt "bvh=--light-sampler bvh"]
        [--cycles light-tree,no-light-tree] [--threshold 1e-2] [--runs 1]
        [--out target/cycles-bench]

--reference: a converged EXR of the same scene at the same size (render it
with vkpt at many spp, or with --cycles-reference N to let Cycles render it
first at N spp with its light tree). --vkpt LABEL=ARGS adds a vkpt series
rendered as `target/release/vkpt SCENE --spp S --width W --height H
--device cpu -q -o OUT.exr ARGS` (later flags win); without any, one series
`vkpt` with no extra flags.

Cycles comes from PyPI `bpy` 5.2, which needs Python 3.13: the first run
makes target/cycles-venv with pyenv's python3.13 (or $CYCLES_PYTHON) and
`pip install bpy==5.2.*`; each Cycles render runs this file again in that
Python (`--cycles-worker`). The worker imports the glTF with Blender's own
importer, renders with the file's camera and these settings, chosen to
match vkpt's estimator rather than Cycles' production defaults:

    device CPU, threads = this machine's cores; no denoising, no adaptive
    sampling; clamping off (direct and indirect); filter: box, 1 pixel;
    bounces: 1024 of every kind (vkpt has no depth limit; both end paths
    by Russian roulette), caustics on, filter glossy 0; world black;
    light tree on or off (`cycles` series light-tree / no-light-tree);
    the seed varies per run.

Time is each process's wall time from start to exit (Python start-up,
import bpy, glTF import, BVH, render, EXR write for Cycles; load, BVH,
render, EXR write for vkpt); the worker also prints its render time.
relMSE is `vkpt compare`'s, of each image against --reference.
"""

import argparse
import math
import os
import re
import shlex
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "target", "cycles-venv")


# --------------------------------------------------------------------------
# The worker: runs inside Blender's Python module.

def cycles_worker(argv):
    p = argparse.ArgumentParser()
    p.add_argument("--cycles-worker", action="store_true")
    p.add_argument("--scene", required=True)
    p.add_argument("--spp", type=int, required=True)
    p.add_argument("--width", type=int, required=True)
    p.add_argument("--height", type=int, required=True)
    p.add_argument("--light-tree", type=int, required=True)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--output", required=True)
    a = p.parse_args(argv)

    import bpy  # noqa: PLC0415 (only in the worker's Python)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(a.scene))
    scene = bpy.context.scene
    cameras = [o for o in scene.objects if o.type == "CAMERA"]
    if not cameras:
        sys.exit("cycles worker: %s has no camera" % a.scene)
    scene.camera = cameras[0]
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world

    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = 1024
    c.diffuse_bounces = 1024
    c.glossy_bounces = 1024
    c.transmission_bounces = 1024
    c.volume_bounces = 1024
    c.transparent_max_bounces = 1024
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.use_light_tree = bool(a.light_tree)
    c.seed = a.seed
    scene.render.threads_mode = "FIXED"
    scene.render.threads = os.cpu_count() or 1
    scene.render.resolution_x = a.width
    scene.render.resolution_y = a.height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.abspath(a.output)

    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print("cycles render %.3f s" % (time.perf_counter() - start), flush=True)


# --------------------------------------------------------------------------
# The driver.

def ensure_venv():
    python = os.path.join(VENV, "bin", "python")
    if os.path.exists(python):
        return python
    base = os.environ.get("CYCLES_PYTHON") or os.path.expanduser("~/.pyenv/versions/3.13.0/bin/python3.13")
    if not os.path.exists(base):
        sys.exit("bpy 5.2 needs Python 3.13: set CYCLES_PYTHON to a python3.13")
    subprocess.run([base, "-m", "venv", VENV], check=True)
    subprocess.run([python, "-m", "pip", "install", "-q", "bpy==5.2.*"], check=True)
    return python


def timed(cmd):
    start = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    secs = time.perf_counter() - start
    if r.returncode != 0:
        sys.exit("failed (%d): %s\n%s%s" % (r.returncode, " ".join(map(shlex.quote, cmd)),
                                            r.stdout[-2000:], r.stderr[-2000:]))
    return secs, r.stdout + r.stderr


def rel_mse(vkpt, image, reference):
    r = subprocess.run([vkpt, "compare", image, reference], capture_output=True, text=True)
    m = re.search(r"^\s+relMSE\s+([-+0-9.eE]+)$", r.stdout + r.stderr, re.M)
    if not m:
        sys.exit("vkpt compare printed no relMSE for %s:\n%s%s" % (image, r.stdout, r.stderr))
    return float(m.group(1))


def cycles_cmd(python, scene, spp, args, light_tree, seed, out):
    return [python, os.path.abspath(__file__), "--cycles-worker", "--scene", scene, "--spp", str(spp),
            "--width", str(args.width), "--height", str(args.height), "--light-tree", str(light_tree),
            "--seed", str(seed), "--output", out]


def time_to(curve, threshold):
    """The first crossing of `threshold` by (seconds, relMSE) points, log-log interpolated."""
    if curve and curve[0][1] <= threshold:
        return curve[0][0]
    for (tp, rp), (t, r) in zip(curve, curve[1:]):
        if r <= threshold:
            f = (math.log(threshold) - math.log(rp)) / (math.log(r) - math.log(rp))
            return math.exp(math.log(tp) + f * (math.log(t) - math.log(tp)))
    return None


def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def main():
    if "--cycles-worker" in sys.argv:
        cycles_worker(sys.argv[1:])
        return
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--reference")
    p.add_argument("--cycles-reference", type=int, default=0, metavar="SPP")
    p.add_argument("--spp", default="4,16,64,256")
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--height", type=int, default=128)
    p.add_argument("--vkpt", action="append", default=[], metavar="LABEL=ARGS")
    p.add_argument("--vkpt-binary", default=os.path.join(ROOT, "target", "release", "vkpt"))
    p.add_argument("--cycles", default="light-tree", help="comma-separated: light-tree, no-light-tree, or none")
    p.add_argument("--threshold", type=float, default=1e-2)
    p.add_argument("--runs", type=int, default=1)
    p.add_argument("--out", default=os.path.join(ROOT, "target", "cycles-bench"))
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    scene = os.path.abspath(args.scene)
    steps = [int(s) for s in args.spp.split(",")]
    cycles = [] if args.cycles == "none" else args.cycles.split(",")
    python = ensure_venv() if cycles or args.cycles_reference else None

    reference = args.reference
    if args.cycles_reference:
        reference = os.path.join(args.out, "cycles-reference-%d.exr" % args.cycles_reference)
        if not os.path.exists(reference):
            secs, _ = timed(cycles_cmd(python, scene, args.cycles_reference, args, 1, 12345, reference))
            print("Cycles reference, %d spp: %.1f s" % (args.cycles_reference, secs))
    if not reference:
        sys.exit("give --reference REF.exr or --cycles-reference SPP")

    series = []
    for spec in args.vkpt or ["vkpt="]:
        label, _, extra = spec.partition("=")
        series.append((label, "vkpt", shlex.split(extra)))
    for kind in cycles:
        if kind not in ("light-tree", "no-light-tree"):
            sys.exit("--cycles: light-tree, no-light-tree or none, not %r" % kind)
        series.append(("cycles " + kind, "cycles", 1 if kind == "light-tree" else 0))

    curves = {label: [] for label, _, _ in series}
    print("%s, %dx%d, relMSE against %s" % (args.scene, args.width, args.height, reference))
    for spp in steps:
        cells = []
        for label, kind, extra in series:
            runs = []
            for run in range(args.runs):
                out = os.path.join(args.out, "%s-%04d-%d.exr" % (re.sub(r"\W+", "-", label), spp, run))
                if kind == "vkpt":
                    cmd = [args.vkpt_binary, scene, "--spp", str(spp), "--width", str(args.width),
                           "--height", str(args.height), "--device", "cpu", "--seed", str(run), "-q",
                           "-o", out] + extra
                else:
                    cmd = cycles_cmd(python, scene, spp, args, extra, run, out)
                secs, _ = timed(cmd)
                runs.append((secs, rel_mse(args.vkpt_binary, out, reference)))
            secs, rel = median([s for s, _ in runs]), median([r for _, r in runs])
            curves[label].append((secs, rel))
            cells.append("%s %.2f s %.3e" % (label, secs, rel))
        print("%5d spp | %s" % (spp, " | ".join(cells)), flush=True)

    print("\n| series | " + " | ".join("%d spp" % s for s in steps) + " | time to relMSE %.0e |" % args.threshold)
    print("|---|" + "---|" * (len(steps) + 1))
    for label, _, _ in series:
        t = time_to(curves[label], args.threshold)
        print("| %s | %s | %s |" % (label, " | ".join("%.2f s, %.2e" % c for c in curves[label]),
                                    "%.2f s" % t if t else "not reached"))


if __name__ == "__main__":
    main()
