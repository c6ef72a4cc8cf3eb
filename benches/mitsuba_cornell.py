#!/usr/bin/env python3
"""Mitsuba 3 against vkpt on the same scene, side by side in one run: speed
and time to reach relMSE 1e-2 and 1e-3 against one converged reference, for
five renderers on the same CPU (or those --renderers names). Not run by CI.

    cargo build --release
    python3 benches/mitsuba_cornell.py [--scene cornell|spheres|both]
        [--spp 1,2,...,256] [--reference-spp N] [--converged-spp N] [--out DIR]
        [--renderers scalar_rgb,cpu]
    python3 benches/mitsuba_cornell.py --whole-process 256 [--runs 3]

The first run makes a virtual environment, target/mitsuba-venv, installs
Mitsuba 3 from PyPI into it and runs itself again with that Python (Debian:
`apt-get install -y python3-venv` for the venv). Mitsuba's LLVM variant needs
a libLLVM shared library, and a recent one: with Debian 12's libllvm15 (the
one Mesa's lavapipe uses) Dr.Jit 1.5 aborts compiling its kernel, with
libllvm19 (`apt-get install -y libllvm19`; Debian 12 has 19.1.7) it works.
The script points DRJIT_LIBLLVM_PATH at the newest libLLVM it finds unless
that variable is set.

Renderers, each measured at every spp of --spp:

    Mitsuba llvm_ad_rgb   Mitsuba's JIT-compiled vectorised back end (LLVM)
    vkpt lavapipe         vkpt's Vulkan kernels on Mesa's CPU Vulkan driver
    vkpt lavapipe indep.  the same with `--sampler independent`
    vkpt lavapipe loop    the same with `--schedule loop` (one kernel runs
                          each path to its end)
    Mitsuba scalar_rgb    Mitsuba's plain C++ back end (one ray at a time on
                          each thread)
    vkpt cpu              vkpt's CPU back end (`--device cpu`), which traces
                          the same paths as the Vulkan kernels
    vkpt cpu indep.       the same with `--sampler independent`

The "indep." rows draw independent random numbers, as Mitsuba's default
sampler does, so their samples/s compare the same work per sample; vkpt's
default, Owen-scrambled Sobol, costs more per sample (two hashes and two
bit reversals more per draw: the CPU back end renders about 10 % more
samples/s without it) and buys a lower error per sample on smooth
integrands.

They take turns at each spp in that order, so load on the shared machine
hits all alike. With --seeds N each renderer renders each step with N
seeds (Mitsuba's 1..N, vkpt's 0..N-1) and the step's time and relMSE are
the medians: where rare bright paths (caustics) make one render's relMSE
heavy-tailed, as in cornell-spheres, one seed's time to an error is noise.
Each row reports samples per second at the largest spp, the time to reach relMSE 1e-2 and 1e-3 (first crossing, log-log interpolated;
if not reached within the spp list, a marked extrapolation assuming
relMSE x time stays constant, from the median of the last three steps), and
the ratios vkpt lavapipe (both schedules) / Mitsuba llvm
and vkpt cpu / Mitsuba scalar (time ratios below 1: vkpt is faster).

Scenes (--scene), both built from scenes/generate.py's data, so the two
renderers get the same triangles (rounded to 0.1 micrometre as in the glTF):

    cornell   scenes/cornell-box.gltf: diffuse walls and boxes (CORNELL_MM)
    spheres   scenes/cornell-spheres.gltf: the same room without the boxes,
              a solid glass sphere (Mitsuba `dielectric`, int_ior 1.5,
              ext_ior 1) and a white perfect mirror sphere (`conductor`,
              material "none"), flat-shaded UV spheres (CORNELL_SPHERES_MM)

Both: a one-sided area light of radiance (17, 12, 4) facing down, the glTF
camera (at (0.278, 0.273, -0.8) looking down +Z, vertical fov 39.3077
degrees), a box pixel filter, the path integrator with no depth limit
(max_depth -1, as vkpt's default) and, unless --mitsuba-sampler says
otherwise, the independent sampler (vkpt renders with its default, Sobol,
which on the diffuse box reaches a lower relMSE at equal spp), at 256x256,
face normals only (no smooth shading normals for the renderers to bend
differently). The spheres scene is far noisier (caustics through the glass
seen only by paths that hit the light): by default it stops at 512 spp and
its reference (4096 spp) is too noisy to time relMSE 1e-3.

Timing: Mitsuba's first render of each variant (1 spp) is an untimed warm-up
(the LLVM variant JIT-compiles its kernel then; later renders reuse it), and
each `vkpt bench` call times renders after its own warm-up (its start-up is
not counted). Every image is measured against one reference per scene, a
vkpt render at --reference-spp (cached by `vkpt bench`), with `vkpt
compare`'s relMSE (mean of (x - ref)^2 / (ref^2 + 0.01)). Before timing
anything, a converged Mitsuba image (--converged-spp, llvm variant) is
checked against that reference: `vkpt compare`'s report, and per-channel
image means with their relative difference and a z-score (Mitsuba's
variance taken as the reference's scaled by the spp ratio: the same
estimator), also for the worst 32x32 tile.
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
VENV = os.path.join(ROOT, "target", "mitsuba-venv")
MITSUBA = "mitsuba==3.9.1"  # the version this script was checked with
sys.path.insert(0, os.path.join(ROOT, "scenes"))
import generate  # noqa: E402  (the scenes' geometry, shared with the glTF)

SIZE = 256
COLOURS = {
    "white": [0.725, 0.71, 0.68],
    "red": [0.63, 0.065, 0.05],
    "green": [0.14, 0.45, 0.091],
    "light": [0.78, 0.78, 0.78],
}
EMISSION = [17.0, 12.0, 4.0]
SCENES = {
    # name: (glTF file, default spp steps, default reference spp)
    "cornell": ("cornell-box.gltf", "1,2,4,8,16,32,64,128,256", 2048),
    "spheres": ("cornell-spheres.gltf", "1,2,4,8,16,32,64,128,256,512", 4096),
}
# (label, kind): the order they take turns in at each spp.
# A vkpt kind is DEVICE[:SCHEDULE][+SAMPLER] (vkpt's --device, --schedule,
# --sampler); "+independent" draws the same kind of random numbers as
# Mitsuba's independent sampler, so samples/s compares the same work.
# Rings of latitude of each UV sphere in "spheres" (twice as many segments
# of longitude): 24 is scenes/cornell-spheres.gltf's 4,428 triangles;
# --sphere-rings sets it (64: 32,268 triangles).
SPHERE_RINGS = 24
RENDERERS = [
    ("Mitsuba llvm_ad_rgb", "llvm_ad_rgb"),
    ("vkpt lavapipe", "lavapipe"),
    ("vkpt lavapipe indep.", "lavapipe+independent"),
    ("vkpt lavapipe loop", "lavapipe:loop"),
    ("Mitsuba scalar_rgb", "scalar_rgb"),
    ("vkpt cpu", "cpu"),
    ("vkpt cpu indep.", "cpu+independent"),
]
RATIOS = [("vkpt lavapipe", "Mitsuba llvm_ad_rgb"), ("vkpt lavapipe indep.", "Mitsuba llvm_ad_rgb"),
          ("vkpt lavapipe loop", "Mitsuba llvm_ad_rgb"),
          ("vkpt cpu", "Mitsuba llvm_ad_rgb"), ("vkpt cpu indep.", "Mitsuba llvm_ad_rgb"),
          ("vkpt cpu", "Mitsuba scalar_rgb"), ("vkpt cpu indep.", "Mitsuba scalar_rgb")]


# --------------------------------------------------------------------------
# Mitsuba in a virtual environment of its own.

def ensure_mitsuba():
    """Import Mitsuba, or make target/mitsuba-venv with it and run this
    script again with the venv's Python."""
    try:
        import mitsuba  # noqa: F401
        return
    except ImportError:
        pass
    python = os.path.join(VENV, "bin", "python")
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        sys.exit("mitsuba is not importable in %s: `%s -m pip install %s`" % (VENV, python, MITSUBA))
    if not os.path.exists(python):
        print("making %s (Python venv for Mitsuba)" % VENV, flush=True)
        if subprocess.run([sys.executable, "-m", "venv", VENV]).returncode != 0:
            sys.exit("python3 -m venv failed (Debian: apt-get install -y python3-venv)")
    probe = subprocess.run([python, "-c", "import mitsuba"], capture_output=True)
    if probe.returncode != 0:
        print("installing %s into %s" % (MITSUBA, VENV), flush=True)
        if subprocess.run([python, "-m", "pip", "install", "-q", MITSUBA]).returncode != 0:
            sys.exit("pip install %s failed" % MITSUBA)
    os.execv(python, [python, os.path.abspath(__file__)] + sys.argv[1:])


def choose_libllvm():
    """Point Dr.Jit at the newest libLLVM on the system (unless
    DRJIT_LIBLLVM_PATH is set): Dr.Jit 1.5 emits llvm.minimum, which LLVM 15
    cannot compile for x86 ("LLVM ERROR: Cannot select: ... fminimum",
    aborting the process); LLVM 19 can."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return
    found = []
    for d in ["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib",
              "/usr/local/lib"]:
        if not os.path.isdir(d):
            continue
        for name in os.listdir(d):
            m = re.match(r"libLLVM(?:-|\.so\.)(\d+)", name)
            if m:
                found.append((int(m.group(1)), os.path.join(d, name)))
    if not found:
        sys.exit("no libLLVM found for Mitsuba's llvm_ad_rgb (Debian: apt-get install -y libllvm19), "
                 "or set DRJIT_LIBLLVM_PATH")
    version, path = max(found)
    if version < 19:
        print("warning: newest libLLVM is %d (%s); Dr.Jit aborted with LLVM 15 here: "
              "apt-get install -y libllvm19" % (version, path), flush=True)
    os.environ["DRJIT_LIBLLVM_PATH"] = path


# --------------------------------------------------------------------------
# The Mitsuba scenes, from scenes/generate.py's data.

def write_obj(path, triangles):
    with open(path, "w") as f:
        for tri in triangles:
            for p in tri:
                f.write("v %.7f %.7f %.7f\n" % tuple(p))
        for i in range(len(triangles)):
            f.write("f %d %d %d\n" % (3 * i + 1, 3 * i + 2, 3 * i + 3))


def obj_shape(work, name, triangles, bsdf):
    path = os.path.join(work, name + ".obj")
    write_obj(path, triangles)
    return {"type": "obj", "filename": path, "face_normals": True, "bsdf": bsdf}


def mitsuba_scene(mi, work, which, sampler):
    """The Cornell box ("cornell") or its glass and mirror spheres variant
    ("spheres") as a Mitsuba scene dictionary."""
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
            "sampler": {"type": sampler, "sample_count": 1},
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
        if which == "spheres" and name in generate.CORNELL_SPHERES_WITHOUT:
            continue
        tris = [
            [[round(c * 0.001, 7) for c in p] for p in tri]
            for tri in generate.oriented_triangles(quads, orientation)
        ]
        bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": COLOURS[material]}}
        scene[name] = obj_shape(work, name, tris, bsdf)
        if material == "light":
            # Mitsuba's area emitter is one-sided, on the side of the
            # triangle's normal (counter-clockwise winding): down, as in glTF.
            scene[name]["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": EMISSION}}
    if which == "spheres":
        bsdfs = {
            # Solid glass: the triangles face outward, so int_ior is inside.
            "glass": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
            # No material: a perfect mirror of reflectance 1.
            "mirror": {"type": "conductor", "material": "none"},
        }
        for name, (material, centre, radius) in generate.CORNELL_SPHERES_MM.items():
            tris = generate.uv_sphere_triangles(centre, radius, SPHERE_RINGS, 2 * SPHERE_RINGS)
            scene[name] = obj_shape(work, name, tris, bsdfs[material])
    return scene


class Mitsuba:
    """One loaded scene per variant; render() switches to the variant."""

    def __init__(self, work, which, sampler):
        import drjit as dr
        import mitsuba as mi

        self.mi, self.dr, self.scenes = mi, dr, {}
        for variant in ["scalar_rgb", "llvm_ad_rgb"]:
            mi.set_variant(variant)
            self.scenes[variant] = mi.load_dict(mitsuba_scene(mi, work, which, sampler))
            self.render(variant, 1, 0)  # warm-up (the LLVM variant's JIT)

    def render(self, variant, spp, seed):
        """Renders, returning (image, seconds)."""
        self.mi.set_variant(variant)
        start = time.perf_counter()
        image = self.mi.render(self.scenes[variant], spp=spp, seed=seed)
        self.dr.eval(image)
        self.dr.sync_thread()
        return image, time.perf_counter() - start

    def write(self, variant, image, path):
        self.mi.set_variant(variant)
        self.mi.util.write_bitmap(path, image, write_async=False)

    def channels(self, path):
        """An EXR's named float channels as flat lists (row-major pixels)."""
        mi = self.mi
        mi.set_variant("scalar_rgb")
        bitmap = mi.Bitmap(path)
        names = [f.name for f in bitmap.struct_()]
        flat = list(mi.TensorXf(bitmap).array)
        n = len(names)
        return {name: flat[i::n] for i, name in enumerate(names)}


# --------------------------------------------------------------------------
# vkpt.

def vkpt_bench(args, gltf, device, spp, out_dir, reference=None, reference_spp=None, seed=0):
    """`vkpt bench` of one step on one device: its stdout and CSV row."""
    # DEVICE[:SCHEDULE][+SAMPLER], e.g. lavapipe:loop, cpu+independent.
    device, _, sampler = device.partition("+")
    device, _, schedule = device.partition(":")
    cmd = [args.vkpt, "bench", gltf, "--width", str(SIZE), "--device", device,
           "--spp", str(spp), "--seed", str(seed), "-o", out_dir]
    cmd += ["--schedule", schedule] if schedule else []
    cmd += ["--sampler", sampler] if sampler else []
    cmd += ["--reference", reference] if reference else ["--reference-spp", str(reference_spp)]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit("$ %s\nvkpt bench failed: %s" % (" ".join(cmd), out.stderr))
    with open(os.path.join(out_dir, "bench.csv")) as f:
        row = next(csv.DictReader(f))
    return cmd, out.stdout, row


def vkpt_compare(vkpt, a, b):
    """`vkpt compare A B`: its report and relMSE of A against B."""
    out = subprocess.run([vkpt, "compare", a, b], capture_output=True, text=True)
    if out.returncode == 2:
        sys.exit("vkpt compare failed: " + out.stderr)
    m = re.search(r"relMSE of .* against .*: ([0-9.eE+-]+)", out.stdout)
    return out.stdout, float(m.group(1))


# --------------------------------------------------------------------------
# One scene.

def scene_gltf(args, which):
    """The scene's glTF: the bundled one, or "spheres" with --sphere-rings
    other than 24, written once into --out by scenes/generate.py."""
    gltf_name = SCENES[which][0]
    if which != "spheres" or SPHERE_RINGS == 24:
        return gltf_name, os.path.join(ROOT, "scenes", gltf_name)
    gltf_name = "cornell-spheres-rings%d.gltf" % SPHERE_RINGS
    path = os.path.join(args.out, gltf_name)
    if not os.path.exists(path):
        os.makedirs(args.out, exist_ok=True)
        generate.cornell_box(path, glass_and_mirror=True, sphere_rings=SPHERE_RINGS)
    return gltf_name, path


def bench_scene(args, which):
    started = time.perf_counter()
    _, default_spp, default_ref_spp = SCENES[which]
    gltf_name, gltf = scene_gltf(args, which)
    steps = [int(s) for s in (args.spp or default_spp).split(",")]
    reference_spp = args.reference_spp or default_ref_spp
    out = os.path.join(args.out, which + suffix())
    os.makedirs(out, exist_ok=True)
    print("\n=== %s (%s), %dx%d, spp %s ===" % (which, gltf_name, SIZE, SIZE, ",".join(map(str, steps))))

    # The one reference: rendered (once, then cached) by `vkpt bench`.
    start = time.perf_counter()
    cmd, stdout, _ = vkpt_bench(args, gltf, args.reference_device, 1, os.path.join(out, "reference"),
                                reference_spp=reference_spp)
    print("$ " + " ".join(cmd))
    print(stdout.rstrip())
    print("(%.1f s)" % (time.perf_counter() - start))
    m = re.search(r"reference (\S+\.exr) \(its own relMSE ([^)]*)\)", stdout)
    reference, reference_rel = m.group(1), m.group(2)

    mitsuba = Mitsuba(out, which, args.mitsuba_sampler)
    if args.converged_spp > 0:
        check_convergence(args, mitsuba, out, reference, reference_spp)

    renderers = chosen_renderers(args)
    rows = {label: [] for label, _ in renderers}
    for spp in steps:
        line = []
        for label, kind in renderers:
            runs = []
            for k in range(args.seeds):
                if kind.endswith("_rgb"):
                    image, secs = mitsuba.render(kind, spp, 1 + k)
                    exr = os.path.join(out, "mitsuba-%s-%04d.exr" % (kind, spp))
                    mitsuba.write(kind, image, exr)
                    _, rel = vkpt_compare(args.vkpt, exr, reference)
                else:
                    folder = "vkpt-%s-%04d" % (kind.replace(":", "-").replace("+", "-"), spp)
                    _, _, row = vkpt_bench(args, gltf, kind, spp, os.path.join(out, folder),
                                           reference=reference, seed=k)
                    secs, rel = float(row["wall_s"]), float(row["rel_mse"])
                runs.append((secs, rel))
            secs, rel = median([s for s, _ in runs]), median([r for _, r in runs])
            rows[label].append((secs, rel, spp))
            spread = " (%.2e-%.2e)" % (min(r for _, r in runs), max(r for _, r in runs)) if args.seeds > 1 else ""
            line.append("%s %.3f s %.2e%s" % (label, secs, rel, spread))
        print("%4d spp: %s" % (spp, " | ".join(line)), flush=True)
    print("\nrelMSE against the reference (%d spp, its own relMSE %s):" % (reference_spp, reference_rel))
    report_speed(rows)
    print("%s: %.0f s" % (which, time.perf_counter() - started))


def check_convergence(args, mitsuba, out, reference, reference_spp):
    """Mitsuba's converged image against vkpt's reference."""
    image, secs = mitsuba.render("llvm_ad_rgb", args.converged_spp, 3)
    converged = os.path.join(out, "mitsuba-converged.exr")
    mitsuba.write("llvm_ad_rgb", image, converged)
    report, _ = vkpt_compare(args.vkpt, converged, reference)
    print("\nMitsuba llvm_ad_rgb at %d spp (%.1f s) against vkpt's reference:" % (args.converged_spp, secs))
    print("$ vkpt compare %s %s" % (converged, reference))
    print(report.rstrip())

    mine, ref = mitsuba.channels(converged), mitsuba.channels(reference)
    # Variance of Mitsuba's pixel means: the reference's, scaled by spp.
    scale_var = 1.0 + reference_spp / args.converged_spp
    print("per-channel image means (z: difference over its standard error):")
    for c in "RGB":
        m, r, v = mine[c], ref[c], ref["variance." + c]
        n = len(r)
        mean_m, mean_r = sum(m) / n, sum(r) / n
        se = math.sqrt(sum(v) * scale_var) / n
        print("  %s: Mitsuba %.5f  vkpt %.5f  Mitsuba/vkpt - 1 = %+.4f  z = %+.1f"
              % (c, mean_m, mean_r, mean_m / mean_r - 1.0, (mean_m - mean_r) / se))
    # The 32x32 tile whose luminance differs most (in standard errors).
    worst = None
    for ty in range(0, SIZE, 32):
        for tx in range(0, SIZE, 32):
            idx = [y * SIZE + x for y in range(ty, ty + 32) for x in range(tx, tx + 32)]
            lum = lambda ch, i: 0.2126 * ch["R"][i] + 0.7152 * ch["G"][i] + 0.0722 * ch["B"][i]  # noqa: E731
            var = lambda i: (0.2126 ** 2 * ref["variance.R"][i] + 0.7152 ** 2 * ref["variance.G"][i]  # noqa: E731
                             + 0.0722 ** 2 * ref["variance.B"][i])
            tile_m = sum(lum(mine, i) for i in idx) / len(idx)
            tile_r = sum(lum(ref, i) for i in idx) / len(idx)
            se = math.sqrt(sum(var(i) for i in idx) * scale_var) / len(idx)
            z = (tile_m - tile_r) / se if se > 0 else 0.0
            if worst is None or abs(z) > abs(worst[0]):
                worst = (z, tx, ty, tile_m, tile_r)
    z, tx, ty, tile_m, tile_r = worst
    print("  worst 32x32 tile (x %d-%d, y %d-%d from the top left): luminance Mitsuba %.5f vkpt %.5f, z = %+.1f"
          % (tx, tx + 31, ty, ty + 31, tile_m, tile_r, z))
    print("  (%d tiles: |z| up to about 3 is expected by chance)" % ((SIZE // 32) ** 2))


# --------------------------------------------------------------------------
# The table.

def median(values):
    """The middle value (the mean of the middle two for an even count)."""
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


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


def chosen_renderers(args):
    """RENDERERS whose kind --renderers names, in RENDERERS' order."""
    if not args.renderers:
        return RENDERERS
    kinds = args.renderers.split(",")
    unknown = [k for k in kinds if k not in [kind for _, kind in RENDERERS]]
    if unknown:
        sys.exit("--renderers: unknown %s (known: %s)" % (", ".join(unknown), ", ".join(k for _, k in RENDERERS)))
    return [(label, kind) for label, kind in RENDERERS if kind in kinds]


def report_speed(rows):
    pixels = SIZE * SIZE
    print("%-20s %11s %7s %16s %16s" % ("renderer", "Msamples/s", "at spp", "to relMSE 1e-2", "to relMSE 1e-3"))
    summary = {}
    for label in rows:
        t_big, _, spp_big = rows[label][-1]
        rate = pixels * spp_big / t_big / 1e6
        curve = [(t, r) for t, r, _ in rows[label]]
        times, cells, marks = [], [], []
        for threshold in [1e-2, 1e-3]:
            t = time_to(curve, threshold)
            if t is not None:
                times.append(t)
                marks.append("")
                cells.append("%.2f s" % t)
            else:
                # relMSE ~ 1/time for an unbiased estimator: relMSE x time
                # from the last three steps, their median (one firefly in
                # one step does not decide it).
                t = sorted(t * r for t, r in curve[-3:])[(min(3, len(curve)) - 1) // 2] / threshold
                times.append(t)
                marks.append("~")
                cells.append("~%.0f s (extrap.)" % t)
        summary[label] = (rate, times, marks)
        print("%-20s %11.3f %7d %16s %16s" % (label, rate, spp_big, cells[0], cells[1]))
    for a, b in RATIOS:
        if a not in summary or b not in summary:
            continue
        (ra, ta, ma), (rb, tb, mb) = summary[a], summary[b]
        ratio = ["%s%.2f" % ("~" if ma[i] or mb[i] else "", ta[i] / tb[i]) for i in range(2)]
        print("%s / %s: throughput %.2f, time to 1e-2 %s, time to 1e-3 %s" % (a, b, ra / rb, ratio[0], ratio[1]))
    print("(time ratios below 1: vkpt is faster; ~ marks extrapolated times)")


def mitsuba_once(variant, which, spp, out):
    """One whole Mitsuba process's work, as a user's script does it: import,
    load the scene, render, write the EXR (run by --whole-process)."""
    import tempfile

    import mitsuba as mi

    mi.set_variant(variant)
    with tempfile.TemporaryDirectory() as work:
        scene = mi.load_dict(mitsuba_scene(mi, work, which, "independent"))
        image = mi.render(scene, spp=spp)
        mi.util.write_bitmap(out, image, write_async=False)


def whole_process(args, which):
    """Wall time of whole processes rendering the scene at --whole-process
    spp: vkpt as a user runs it (each --device) and a fresh Python process
    per Mitsuba variant; one untimed round first (it fills Dr.Jit's kernel
    cache and vkpt's --device auto measurement, as any earlier run would),
    then --runs rounds taking turns; medians."""
    spp = args.whole_process
    _, gltf = scene_gltf(args, which)
    out = os.path.join(args.out, which + suffix(), "whole-process")
    os.makedirs(out, exist_ok=True)
    me = os.path.abspath(__file__)
    def vkpt(device):
        return [args.vkpt, gltf, "--spp", str(spp), "--width", str(SIZE), "-q",
                "--device", device, "-o", os.path.join(out, device + ".exr")]

    def mitsuba(variant):
        return [sys.executable, me, "--mitsuba-once", variant, which, str(spp),
                os.path.join(out, variant + ".exr"), str(SPHERE_RINGS)]

    cmds = [
        ("Mitsuba llvm_ad_rgb", mitsuba("llvm_ad_rgb")),
        ("vkpt --device auto", vkpt("auto")),
        ("vkpt --device lavapipe", vkpt("lavapipe")),
        ("Mitsuba scalar_rgb", mitsuba("scalar_rgb")),
        ("vkpt --device cpu", vkpt("cpu")),
    ]
    times = {label: [] for label, _ in cmds}
    print("=== %s, %dx%d, %d spp, whole processes ===" % (which, SIZE, SIZE, spp), flush=True)
    for run in range(args.runs + 1):
        for label, cmd in cmds:
            start = time.perf_counter()
            done = subprocess.run(cmd, capture_output=True, text=True)
            seconds = time.perf_counter() - start
            if done.returncode != 0:
                sys.exit("%s failed:\n%s" % (" ".join(cmd), done.stderr))
            if run > 0:
                times[label].append(seconds)
        if run > 0:
            print("  run %d: %s" % (run, " | ".join("%s %.2f s" % (l, t[-1]) for l, t in times.items())),
                  flush=True)
    median = {label: sorted(t)[len(t) // 2] for label, t in times.items()}
    for label, t in median.items():
        print("%-24s %7.2f s" % (label, t))
    for a, b in [("vkpt --device auto", "Mitsuba llvm_ad_rgb"), ("vkpt --device lavapipe", "Mitsuba llvm_ad_rgb"),
                 ("vkpt --device cpu", "Mitsuba scalar_rgb")]:
        print("%s / %s: whole-process time %.2f (below 1: vkpt is faster)" % (a, b, median[a] / median[b]))


def suffix():
    """The output folder's suffix for --sphere-rings other than 24."""
    return "" if SPHERE_RINGS == 24 else "-rings%d" % SPHERE_RINGS


def main():
    global SPHERE_RINGS
    if len(sys.argv) == 7 and sys.argv[1] == "--mitsuba-once":
        SPHERE_RINGS = int(sys.argv[6])
        choose_libllvm()
        mitsuba_once(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5])
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", choices=["cornell", "spheres", "both"], default="both")
    ap.add_argument("--spp", help="spp steps, comma-separated (default: per scene, see SCENES)")
    ap.add_argument("--reference-spp", type=int, help="spp of vkpt's reference (default: per scene)")
    ap.add_argument("--reference-device", default="cpu",
                    help="vkpt back end that renders the reference (both trace the same paths)")
    ap.add_argument("--mitsuba-sampler", default="independent",
                    help="Mitsuba's sampler plugin (vkpt uses its default, Sobol)")
    ap.add_argument("--converged-spp", type=int, default=1024,
                    help="spp of Mitsuba's image checked against vkpt's reference (0: skip)")
    ap.add_argument("--renderers", help="kinds to run, comma-separated, from: %s (default: all)"
                    % ", ".join(kind for _, kind in RENDERERS))
    ap.add_argument("--whole-process", type=int, metavar="SPP",
                    help="instead: time whole processes rendering at SPP (vkpt's --device auto, lavapipe "
                         "and cpu; a fresh Python process per Mitsuba variant)")
    ap.add_argument("--runs", type=int, default=3, help="timed rounds of --whole-process (median)")
    ap.add_argument("--seeds", type=int, default=1,
                    help="renders per step and renderer, with different seeds; the medians are reported")
    ap.add_argument("--sphere-rings", type=int, default=24,
                    help="rings of latitude of each sphere of \"spheres\" (twice as many segments); "
                         "other than 24 writes the scene into --out (64: the room with 32,268 triangles)")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "mitsuba-bench"))
    ap.add_argument("--vkpt", default=os.path.join(ROOT, "target", "release", "vkpt"))
    args = ap.parse_args()
    if args.sphere_rings < 3:
        sys.exit("--sphere-rings must be at least 3")
    SPHERE_RINGS = args.sphere_rings
    if args.seeds < 1:
        sys.exit("--seeds must be at least 1")
    if not os.path.exists(args.vkpt):
        sys.exit("%s not found: cargo build --release" % args.vkpt)
    choose_libllvm()  # before Dr.Jit is imported
    ensure_mitsuba()
    start = time.perf_counter()
    for which in ["cornell", "spheres"] if args.scene == "both" else [args.scene]:
        if args.whole_process:
            whole_process(args, which)
        else:
            bench_scene(args, which)
    print("\nwhole run: %.0f s" % (time.perf_counter() - start))


if __name__ == "__main__":
    main()
