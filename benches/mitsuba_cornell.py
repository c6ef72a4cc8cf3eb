#!/usr/bin/env python3
"""Mitsuba 3 (LLVM back end) against vkpt on the bundled Cornell box, side by
side in one run: speed and time to reach relMSE 1e-2 and 1e-3 against one
converged reference. Not run by CI.

    pip install mitsuba && apt-get install -y libllvm19   # Mitsuba's LLVM variant
    cargo build --release
    python3 benches/mitsuba_cornell.py [--spp 1,2,...,512] [--out DIR]

The Mitsuba scene is built from the same data as scenes/cornell-box.gltf
(scenes/generate.py's CORNELL_MM, triangles and rounding): diffuse
materials, a one-sided area light of radiance (17, 12, 4) facing down, the
glTF camera (at (0.278, 0.273, -0.8) looking down +Z, vertical fov
39.3077 degrees), a box pixel filter, the path integrator with max_depth -1
(no limit) and the independent sampler, at 256x256.

Steps alternate between the two renderers (a Mitsuba render, then
`vkpt bench` at the same spp), so load on the shared machine hits both alike.
Mitsuba's first render (1 spp) is a warm-up that JIT-compiles its kernel
(later spp reuse it: a repeated 64-spp render took the same time), and vkpt's
bench likewise times warmed-up renders (start-up is reported separately).
Both are measured against the reference `vkpt bench` renders and caches
(2048 spp on lavapipe, its own relMSE about 1e-4), with `vkpt compare`'s
relMSE (mean of (x - ref)^2 / (ref^2 + 0.01)). Mitsuba's own converged image
is first checked against that reference.
"""

import argparse
import csv
import math
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scenes"))
import generate  # noqa: E402  (the Cornell box's geometry, shared with the glTF)

SIZE = 256
COLOURS = {
    "white": [0.725, 0.71, 0.68],
    "red": [0.63, 0.065, 0.05],
    "green": [0.14, 0.45, 0.091],
    "light": [0.78, 0.78, 0.78],
}
EMISSION = [17.0, 12.0, 4.0]


def write_obj(path, triangles):
    with open(path, "w") as f:
        for tri in triangles:
            for p in tri:
                f.write("v %.7f %.7f %.7f\n" % tuple(p))
        for i in range(len(triangles)):
            f.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))


def cornell_scene(mi, work, spp):
    """The Cornell box as a Mitsuba scene dictionary."""
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": 39.3077,
            "near_clip": 0.01,
            "far_clip": 100.0,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0.278, 0.273, -0.8], target=[0.278, 0.273, 0.0], up=[0.0, 1.0, 0.0]
            ),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {
                "type": "hdrfilm",
                "width": SIZE,
                "height": SIZE,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
    }
    for name, (material, quads, orientation) in generate.CORNELL_MM.items():
        tris = [
            [[round(c * 0.001, 7) for c in p] for p in tri]
            for tri in generate.oriented_triangles(quads, orientation)
        ]
        path = os.path.join(work, name + ".obj")
        write_obj(path, tris)
        shape = {
            "type": "obj",
            "filename": path,
            "face_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": COLOURS[material]}},
        }
        if material == "light":
            # Mitsuba's area emitter is one-sided, on the side of the
            # triangle's normal (counter-clockwise winding): down, as in glTF.
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": EMISSION}}
        scene[name] = shape
    return scene


def mitsuba_render(mi, dr, scene, spp, seed):
    start = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return image, time.perf_counter() - start


def vkpt_compare(vkpt, a, b):
    """`vkpt compare A B`: its report and relMSE of A against B."""
    out = subprocess.run([vkpt, "compare", a, b], capture_output=True, text=True)
    if out.returncode == 2:
        sys.exit("vkpt compare failed: " + out.stderr)
    m = re.search(r"relMSE of .* against .*: ([0-9.eE+-]+)", out.stdout)
    return out.stdout, float(m.group(1))


def time_to(curve, threshold):
    """The first crossing of `threshold`, log-log interpolated (as src/bench/mod.rs)."""
    if not curve:
        return None
    if curve[0][1] <= threshold:
        return curve[0][0]
    for (tp, rp), (t, r) in zip(curve, curve[1:]):
        if r <= threshold:
            if r <= 0:
                return t
            f = (math.log(threshold) - math.log(rp)) / (math.log(r) - math.log(rp))
            return math.exp(math.log(tp) + f * (math.log(t) - math.log(tp)))
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", default="1,2,4,8,16,32,64,128,256")
    ap.add_argument("--reference-spp", type=int, default=2048)
    ap.add_argument("--converged-spp", type=int, default=1024,
                    help="spp of Mitsuba's image checked against vkpt's reference (0: skip)")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "mitsuba-cornell"))
    ap.add_argument("--vkpt", default=os.path.join(ROOT, "target", "release", "vkpt"))
    args = ap.parse_args()
    steps = [int(s) for s in args.spp.split(",")]
    os.makedirs(args.out, exist_ok=True)

    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    scene = mi.load_dict(cornell_scene(mi, args.out, 1))
    mitsuba_render(mi, dr, scene, 1, 0)  # JIT warm-up

    gltf = os.path.join(ROOT, "scenes", "cornell-box.gltf")
    rows = {"mitsuba": [], "vkpt": []}
    reference = None
    for spp in steps:
        image, secs = mitsuba_render(mi, dr, scene, spp, 1)
        exr = os.path.join(args.out, "mitsuba-%04d.exr" % spp)
        mi.util.write_bitmap(exr, image, write_async=False)

        step_dir = os.path.join(args.out, "vkpt-%04d" % spp)
        cmd = [args.vkpt, "bench", gltf, "--width", str(SIZE), "--device", "lavapipe",
               "--spp", str(spp), "--reference-spp", str(args.reference_spp), "-o", step_dir]
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit("vkpt bench failed: " + out.stderr)
        if reference is None:
            print("$ " + " ".join(cmd))
            print(out.stdout)
            reference = re.search(r"reference (\S+\.exr) \(its own", out.stdout).group(1)
        with open(os.path.join(step_dir, "bench.csv")) as f:
            row = next(csv.DictReader(f))
        rows["vkpt"].append((float(row["wall_s"]), float(row["rel_mse"]), spp))

        _, rel = vkpt_compare(args.vkpt, exr, reference)
        rows["mitsuba"].append((secs, rel, spp))
        print("step %4d spp: mitsuba %.3f s relMSE %.3e | vkpt lavapipe %.3f s relMSE %.3e"
              % (spp, secs, rel, float(row["wall_s"]), float(row["rel_mse"])), flush=True)

    # Does Mitsuba converge to the same image? Its converged render against
    # vkpt's reference (Mitsuba's EXR has no variance layer: metrics only).
    if args.converged_spp > 0:
        check_convergence(mi, dr, scene, args, reference)
    report_speed(rows)


def check_convergence(mi, dr, scene, args, reference):
    image, secs = mitsuba_render(mi, dr, scene, args.converged_spp, 3)
    converged = os.path.join(args.out, "mitsuba-converged.exr")
    mi.util.write_bitmap(converged, image, write_async=False)
    report, _ = vkpt_compare(args.vkpt, converged, reference)
    print("$ vkpt compare %s %s" % (converged, reference))
    print("\nMitsuba %d spp (%.1f s) against vkpt's reference:\n%s" % (args.converged_spp, secs, report))


def report_speed(rows):
    pixels = SIZE * SIZE
    print("%-18s %12s %10s %14s %14s" % ("renderer", "Msamples/s", "at spp", "to relMSE 1e-2", "to relMSE 1e-3"))
    summary = {}
    for name, label in [("mitsuba", "Mitsuba llvm_ad_rgb"), ("vkpt", "vkpt lavapipe")]:
        curve = [(t, r) for t, r, _ in rows[name]]
        t_big, _, spp_big = rows[name][-1]
        rate = pixels * spp_big / t_big / 1e6
        t2, t3 = time_to(curve, 1e-2), time_to(curve, 1e-3)
        summary[name] = (rate, t2, t3)
        fmt = lambda t: "not reached" if t is None else "%.2f s" % t  # noqa: E731
        print("%-18s %12.3f %10d %14s %14s" % (label, rate, spp_big, fmt(t2), fmt(t3)))
    (mr, m2, m3), (vr, v2, v3) = summary["mitsuba"], summary["vkpt"]
    ratio = lambda v, m: "n/a" if v is None or m is None else "%.2f" % (v / m)  # noqa: E731
    print("vkpt / Mitsuba: throughput %.2f, time to 1e-2 %s, time to 1e-3 %s"
          % (vr / mr, ratio(v2, m2), ratio(v3, m3)))


if __name__ == "__main__":
    main()
