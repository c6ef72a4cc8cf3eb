#!/usr/bin/env python3
"""vkpt and Mitsuba 3 side by side on large scenes (benches/large_scenes.py):
whole-process time, render time, samples/s, scene build time and peak
resident memory of each renderer's process, and whether their images agree.
A benchmark, never run by CI.

    cargo build --release
    python3 benches/mitsuba_large.py [--scenes instances-100,forest-10k-nodes,bumpy-5m]
        [--spp 16] [--runs 1] [--vkpt-args "--device vulkan"] [--mitsuba-variants llvm_ad_rgb,scalar_rgb]
        [--llvm-max-instances 1000] [--out target/large-scenes] [--timeout 3600]

--scenes names glTF files in --out without .gltf: bumpy-5m, bumpy-N (N may
end in k or m: bumpy-1.31m, bumpy-1310720), instances-100, forest-10k-nodes,
forest-10k-gpu-instancing, and any of them with -flat (every instance's
triangles baked into world space). A missing file is written first by
benches/large_scenes.py's code (the -flat ones with --flatten).

The first run makes target/mitsuba-venv (Mitsuba 3 and numpy from PyPI) and
runs itself again with that Python, as benches/mitsuba_cornell.py does;
Mitsuba's LLVM variant needs libLLVM 19 or newer (Debian 12:
`apt-get install -y libllvm19`): DRJIT_LIBLLVM_PATH is pointed at the newest
libLLVM found unless it is set.

Each render is a whole separate process, the renderers taking turns (vkpt,
then each Mitsuba variant) --runs times per scene; the table shows medians:

    vkpt     target/release/vkpt SCENE --spp S --width 256 --height 256
             --device cpu -q -o OUT.exr, then --vkpt-args (later flags
             win: --vkpt-args "--device vulkan"). Its summary line gives
             load (glTF read, nodes flattened), BVH (build) and render time
             and samples/s.
    Mitsuba  a fresh Python process: import mitsuba, mi.load_dict of the
             same triangles (read from the glTF by this script's own
             reader and written as binary PLY files, local space; a mesh
             placed once is a shape with its to_world, a mesh placed more
             than once a `shapegroup` with one `instance` per placement),
             mi.render, write the EXR. Load is Python start-up plus
             `import mitsuba`; build is mi.load_dict (PLY reading and
             Embree's BVH); render is mi.render to dr.sync_thread. Before
             the timed rounds one untimed llvm_ad_rgb process renders the
             scene at the same settings: Dr.Jit compiles its kernels then
             and caches them on disk, as any earlier run would.
             llvm_ad_rgb is skipped on scenes of more than
             --llvm-max-instances instances: Dr.Jit traces each instance's
             code into the kernel (mitsuba3 issue #1017). Measured here at
             4 spp, cold kernel cache: 10 instances 3 s, 100 instances 10 s
             (1.9 s once cached), 1,000 instances 97 s and 700 MB; 10,000
             instances ran over 10 minutes and reached 12.6 GB before it was
             stopped. scalar_rgb renders the 10,000 trees in seconds.

Both: the glTF camera (vertical fov, aspect 1, its node's transform;
Mitsuba's camera looks down +Z with +X to the left, glTF's down -Z with +X
to the right: to_world = camera node * diag(-1, 1, -1)), diffuse
reflectance = baseColorFactor (the files' materials are exactly Lambertian),
the light a one-sided area emitter of radiance emissiveFactor *
emissiveStrength over the same diffuse base, shading normals from the
files' NORMALs, the path integrator with no depth limit (max_depth -1),
Mitsuba's independent sampler (vkpt keeps its default, Sobol), a box pixel
filter, 256 x 256, the same spp.

Peak memory is each child's maximum resident set size (os.wait4's
ru_maxrss): processes run one at a time, never two large ones at once.
The images' agreement: each image's mean over pixels and channels, and
Mitsuba's mean relative to vkpt's with a z-score (the standard error of
vkpt's image mean, from its variance layer, counted twice: Mitsuba's is
about as large). A vkpt failure (refusal, out of memory, a crash) is
recorded in the table as its last line of error output, not raised.

The table (Markdown) goes to stdout and to --out/results.md (replaced by
each run), with vkpt's summary lines and notes. Per-run output, EXRs and
logs: --out/renders/SCENE/; Mitsuba's PLY files: --out/mitsuba/SCENE/.
"""

import argparse
import json
import os
import platform
import re
import shlex
import signal
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "target", "mitsuba-venv")
MITSUBA = "mitsuba==3.9.1"  # the version this script was checked with
sys.path.insert(0, os.path.join(ROOT, "benches"))
import large_scenes  # noqa: E402  (the scenes, written when missing)

SIZE = 256
DEFAULT_SCENES = "instances-100,forest-10k-nodes,bumpy-5m"


# --------------------------------------------------------------------------
# Mitsuba in a virtual environment of its own (as benches/mitsuba_cornell.py).

def ensure_mitsuba():
    """Import Mitsuba and numpy, or make target/mitsuba-venv with them and
    run this script again with the venv's Python."""
    try:
        import mitsuba  # noqa: F401
        import numpy  # noqa: F401
        return
    except ImportError:
        pass
    python = os.path.join(VENV, "bin", "python")
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        sys.exit("mitsuba or numpy is not importable in %s: `%s -m pip install %s numpy`" % (VENV, python, MITSUBA))
    if not os.path.exists(python):
        print("making %s (Python venv for Mitsuba)" % VENV, flush=True)
        if subprocess.run([sys.executable, "-m", "venv", VENV]).returncode != 0:
            sys.exit("python3 -m venv failed (Debian: apt-get install -y python3-venv)")
    probe = subprocess.run([python, "-c", "import mitsuba, numpy"], capture_output=True)
    if probe.returncode != 0:
        print("installing %s and numpy into %s" % (MITSUBA, VENV), flush=True)
        if subprocess.run([python, "-m", "pip", "install", "-q", MITSUBA, "numpy"]).returncode != 0:
            sys.exit("pip install %s numpy failed" % MITSUBA)
    os.execv(python, [python, os.path.abspath(__file__)] + sys.argv[1:])


def choose_libllvm():
    """Point Dr.Jit at the newest libLLVM on the system unless
    DRJIT_LIBLLVM_PATH is set (Dr.Jit 1.5 aborts with LLVM 15; 19 works)."""
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
# Reading the glTF files large_scenes.py writes (numpy).

def read_gltf(path):
    """(document, accessor reader) for a .gltf with external buffers."""
    import numpy as np

    with open(path) as f:
        g = json.load(f)
    folder = os.path.dirname(path)
    buffers = [np.memmap(os.path.join(folder, b["uri"]), dtype=np.uint8, mode="r") for b in g["buffers"]]
    dtypes = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
    widths = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}

    def accessor(k):
        a = g["accessors"][k]
        v = g["bufferViews"][a["bufferView"]]
        dtype, width = np.dtype(dtypes[a["componentType"]]), widths[a["type"]]
        start = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = v.get("byteStride", dtype.itemsize * width)
        raw = buffers[v["buffer"]]
        if stride == dtype.itemsize * width:
            data = np.frombuffer(raw, dtype=dtype, count=a["count"] * width, offset=start)
        else:
            rows = np.lib.stride_tricks.as_strided(raw[start:], shape=(a["count"], dtype.itemsize * width),
                                                   strides=(stride, 1))
            data = np.ascontiguousarray(rows).view(dtype)
        return data.reshape(a["count"], width) if width > 1 else data

    return g, accessor


def trs(node):
    """A node's local 4x4 matrix (float64)."""
    import numpy as np

    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    return trs_matrix(node.get("translation", [0, 0, 0]), node.get("rotation", [0, 0, 0, 1]),
                      node.get("scale", [1, 1, 1]))


def trs_matrix(t, q, s):
    import numpy as np

    x, y, z, w = [float(c) for c in q]
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    m = np.eye(4)
    m[:3, :3] = r * np.array(s, dtype=np.float64)[None, :]
    m[:3, 3] = t
    return m


def write_ply(path, positions, normals, indices):
    """Binary little-endian PLY: float x y z nx ny nz, faces as uchar 3 +
    3 int32 (Mitsuba's ply plugin reads it)."""
    import numpy as np

    vert = np.empty(len(positions), dtype=[("p", "<f4", 3), ("n", "<f4", 3)])
    vert["p"], vert["n"] = positions, normals
    faces = np.empty(len(indices) // 3, dtype=[("k", "u1"), ("i", "<i4", 3)])
    faces["k"] = 3
    faces["i"] = indices.reshape(-1, 3)
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
              % (len(positions), len(faces)))
    with open(path + ".part", "wb") as f:
        f.write(header.encode("ascii"))
        vert.tofile(f)
        faces.tofile(f)
    os.replace(path + ".part", path)


def mitsuba_description(gltf, folder):
    """The scene for Mitsuba as JSON-able data (PLY files written into
    folder): camera, materials, shapes with to_world, shape groups with
    instances. Cached: rewritten only when the glTF is newer."""
    import numpy as np

    desc_path = os.path.join(folder, "scene.json")
    if os.path.exists(desc_path) and os.path.getmtime(desc_path) > max(
            os.path.getmtime(gltf), os.path.getmtime(gltf[:-len(".gltf")] + ".bin")):
        with open(desc_path) as f:
            return desc_path, json.load(f)
    os.makedirs(folder, exist_ok=True)
    g, accessor = read_gltf(gltf)

    # World matrices of mesh placements and of the camera.
    placements = {}  # mesh index -> [4x4]
    camera = None

    def visit(k, parent):
        nonlocal camera
        node = g["nodes"][k]
        world = parent @ trs(node)
        if "mesh" in node:
            ext = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
            if ext:
                a = ext["attributes"]
                n = g["accessors"][a["TRANSLATION"]]["count"]
                t = accessor(a["TRANSLATION"]) if "TRANSLATION" in a else np.zeros((n, 3))
                q = accessor(a["ROTATION"]) if "ROTATION" in a else np.tile([0, 0, 0, 1], (n, 1))
                s = accessor(a["SCALE"]) if "SCALE" in a else np.ones((n, 3))
                mats = [world @ trs_matrix(t[i], q[i], s[i]) for i in range(n)]
            else:
                mats = [world]
            placements.setdefault(node["mesh"], []).extend(mats)
        if "camera" in node and camera is None:
            camera = (node["camera"], world)
        for child in node.get("children", []):
            visit(child, world)

    for k in g["scenes"][g.get("scene", 0)]["nodes"]:
        visit(k, np.eye(4))
    if camera is None:
        sys.exit("%s: no camera" % gltf)
    cam = g["cameras"][camera[0]]["perspective"]
    flip = np.diag([-1.0, 1.0, -1.0, 1.0])

    materials = []
    for m in g["materials"]:
        base = m.get("pbrMetallicRoughness", {}).get("baseColorFactor", [1, 1, 1, 1])[:3]
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        emission = [c * strength for c in m.get("emissiveFactor", [0, 0, 0])]
        materials.append({"name": m.get("name", ""), "reflectance": base,
                          "radiance": emission if max(emission) > 0 else None})

    shapes, groups, triangles = [], [], 0
    for mesh_index, mats in placements.items():
        mesh = g["meshes"][mesh_index]
        prims = []
        for p_index, prim in enumerate(mesh["primitives"]):
            ply = os.path.join(folder, "mesh%d-%d.ply" % (mesh_index, p_index))
            idx = accessor(prim["indices"]).astype(np.int32)
            write_ply(ply, accessor(prim["attributes"]["POSITION"]), accessor(prim["attributes"]["NORMAL"]), idx)
            prims.append({"ply": os.path.basename(ply), "material": prim["material"], "triangles": len(idx) // 3})
            triangles += len(idx) // 3 * len(mats)
        if len(mats) == 1:
            for p in prims:
                shapes.append(dict(p, to_world=mats[0].tolist()))
        else:
            groups.append({"name": mesh.get("name", "mesh%d" % mesh_index), "shapes": prims,
                           "instances": [m.tolist() for m in mats]})
    desc = {
        "gltf": os.path.abspath(gltf),
        "camera": {"yfov_degrees": float(np.degrees(cam["yfov"])), "to_world": (camera[1] @ flip).tolist()},
        "materials": materials,
        "shapes": shapes,
        "groups": groups,
        "triangles": triangles,
    }
    with open(desc_path + ".part", "w") as f:
        json.dump(desc, f)
    os.replace(desc_path + ".part", desc_path)
    return desc_path, desc


def mitsuba_dict(mi, desc, folder, spp):
    """The load_dict dictionary of a description."""
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": desc["camera"]["yfov_degrees"],
            "near_clip": 0.01,
            "far_clip": 100.0,
            "to_world": T(desc["camera"]["to_world"]),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
        },
    }
    for k, m in enumerate(desc["materials"]):
        scene["bsdf%d" % k] = {"type": "diffuse", "id": "bsdf%d" % k,
                               "reflectance": {"type": "rgb", "value": m["reflectance"]}}

    def shape(p, to_world=None):
        s = {"type": "ply", "filename": os.path.join(folder, p["ply"]),
             "bsdf": {"type": "ref", "id": "bsdf%d" % p["material"]}}
        if to_world is not None:
            s["to_world"] = T(to_world)
        radiance = desc["materials"][p["material"]]["radiance"]
        if radiance and to_world is not None:
            s["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": radiance}}
        return s

    for k, p in enumerate(desc["shapes"]):
        scene["shape%d" % k] = shape(p, p["to_world"])
    for gk, group in enumerate(desc["groups"]):
        if any(desc["materials"][p["material"]]["radiance"] for p in group["shapes"]):
            print("note: Mitsuba cannot instance emitters: group %s renders without emission" % group["name"],
                  file=sys.stderr)
        sg = {"type": "shapegroup", "id": "group%d" % gk}
        for k, p in enumerate(group["shapes"]):
            sg["shape%d" % k] = shape(p)
        scene["group%d" % gk] = sg
        for i, m in enumerate(group["instances"]):
            scene["group%d_instance%d" % (gk, i)] = {"type": "instance", "shape": {"type": "ref", "id": "group%d" % gk},
                                                     "to_world": T(m)}
    return scene


def mitsuba_child(variant, desc_path, spp, out):
    """One whole Mitsuba process's work (run by --mitsuba-child): prints
    its timings as JSON on the last line."""
    started = time.perf_counter()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(variant)
    with open(desc_path) as f:
        desc = json.load(f)
    loaded = time.perf_counter()
    d = mitsuba_dict(mi, desc, os.path.dirname(desc_path), spp)
    scene = mi.load_dict(d)
    built = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=0)
    dr.eval(image)
    dr.sync_thread()
    rendered = time.perf_counter()
    mi.util.write_bitmap(out, image, write_async=False)
    print(json.dumps({"load_s": loaded - started, "build_s": built - loaded, "render_s": rendered - built}))


# --------------------------------------------------------------------------
# Running a whole process and measuring it.

def run_measured(cmd, log_path, timeout):
    """Runs cmd to its end: (exit code, wall seconds, peak RSS in MB,
    stdout, stderr). Its output goes to log_path(.out/.err)."""
    with open(log_path + ".out", "w") as out, open(log_path + ".err", "w") as err:
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err)
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
    with open(log_path + ".out") as f:
        stdout = f.read()
    with open(log_path + ".err") as f:
        stderr = f.read()
    return proc.returncode, wall, usage.ru_maxrss / 1024.0, stdout, stderr


def failure_line(code, stdout, stderr):
    if code < 0:
        name = signal.Signals(-code).name
        extra = " (killed: out of memory or --timeout?)" if -code == signal.SIGKILL else ""
        return "terminated by %s%s" % (name, extra)
    lines = [l.strip() for l in (stderr + "\n" + stdout).splitlines()
             if l.strip() and not re.match(r"^\d+% ", l.strip())]
    errors = [l for l in lines if l.lower().startswith("error")]
    return "exit %d: %s" % (code, (errors or lines or ["(no output)"])[-1])


def seconds(value, unit):
    return float(value) / (1000.0 if unit == "ms" else 1.0)


def parse_vkpt(stdout):
    """load, BVH and render seconds and samples/s from vkpt's summary."""
    m = re.search(r"load ([0-9.]+) (ms|s), BVH ([0-9.]+) (ms|s)", stdout)
    r = re.search(r"rendered .* at (\d+) spp in ([0-9.]+) s: ([0-9.]+) ([kMG]?)samples/s", stdout)
    if not (m and r):
        return None
    rate = float(r.group(3)) * {"": 1, "k": 1e3, "M": 1e6, "G": 1e9}[r.group(4)]
    return {"load_s": seconds(m.group(1), m.group(2)), "build_s": seconds(m.group(3), m.group(4)),
            "render_s": float(r.group(2)), "samples_per_s": rate}


def image_stats(path, with_variance):
    """(mean over pixels and channels, standard error of that mean or None)."""
    import mitsuba as mi
    import numpy as np

    mi.set_variant("scalar_rgb")
    bitmap = mi.Bitmap(path)
    names = [f.name for f in bitmap.struct_()]
    data = np.array(bitmap, copy=False).reshape(-1, len(names)).astype(np.float64)
    rgb = data[:, [names.index(c) for c in "RGB"]]
    mean = float(rgb.mean())
    se = None
    if with_variance and all("variance." + c in names for c in "RGB"):
        var = data[:, [names.index("variance." + c) for c in "RGB"]]
        # Var of the mean of 3N values, each pixel mean's variance given.
        se = float(np.sqrt(var.sum()) / rgb.size)
    return mean, se


# --------------------------------------------------------------------------

def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def ensure_scene(out, stem):
    """The glTF path of a scene name, written when missing."""
    path = os.path.join(out, stem + ".gltf")
    if os.path.exists(path):
        return path
    flat = stem.endswith("-flat")
    base = stem[:-len("-flat")] if flat else stem
    name = "forest-10k" if base.startswith("forest-10k-") else base
    print("writing %s (benches/large_scenes.py)" % name, flush=True)
    large_scenes.header()
    large_scenes.write_scene(name, out, flatten=flat)
    if not os.path.exists(path):
        sys.exit("%s was not written (scene names: bumpy-5m, bumpy-N, instances-100, forest-10k-nodes, "
                 "forest-10k-gpu-instancing, each with -flat)" % path)
    return path


def bench_scene(args, stem, me):
    gltf = ensure_scene(args.out, stem)
    t0 = time.perf_counter()
    desc_path, desc = mitsuba_description(gltf, os.path.join(args.out, "mitsuba", stem))
    print("\n=== %s: %s triangles placed (%s), %dx%d, %d spp; Mitsuba's PLY files ready in %.1f s ===" % (
        stem, "{:,}".format(desc["triangles"]),
        ", ".join("%s x%d" % (g["name"], len(g["instances"])) for g in desc["groups"]) or "no instancing",
        SIZE, SIZE, args.spp, time.perf_counter() - t0), flush=True)
    renders = os.path.join(args.out, "renders", stem)
    os.makedirs(renders, exist_ok=True)
    vkpt_extra = shlex.split(args.vkpt_args)

    def vkpt_cmd(out):
        return [args.vkpt, gltf, "--spp", str(args.spp), "--width", str(SIZE), "--height", str(SIZE),
                "--device", "cpu", "-q", "-o", out] + vkpt_extra

    def mitsuba_cmd(variant, out):
        return [sys.executable, me, "--mitsuba-child", variant, desc_path, str(args.spp), out]

    renderers = [("vkpt", None)] + [("Mitsuba " + v, v) for v in args.mitsuba_variants.split(",") if v]
    instances = sum(len(g["instances"]) for g in desc["groups"])
    skipped = {}
    if instances > args.llvm_max_instances:
        for label, variant in renderers:
            if variant and variant.startswith("llvm"):
                skipped[label] = ("skipped: %d instances > --llvm-max-instances %d (Dr.Jit traces and compiles "
                                  "code per instance: mitsuba3 issue #1017)" % (instances, args.llvm_max_instances))
        renderers = [(label, v) for label, v in renderers if label not in skipped]
        for label, why in skipped.items():
            print("  %s %s" % (label, why), flush=True)
    if any(v == "llvm_ad_rgb" for _, v in renderers):
        out = os.path.join(renders, "warm-up-llvm_ad_rgb.exr")
        code, wall, peak, stdout, stderr = run_measured(mitsuba_cmd("llvm_ad_rgb", out),
                                                        os.path.join(renders, "warm-up"), args.timeout)
        print("untimed Mitsuba llvm_ad_rgb warm-up (fills Dr.Jit's kernel cache): %.1f s%s" % (
            wall, "" if code == 0 else ", " + failure_line(code, stdout, stderr)), flush=True)
    results = {label: [] for label, _ in renderers}
    notes = []
    for run in range(args.runs):
        for label, variant in renderers:
            tag = "vkpt" if variant is None else variant
            out = os.path.join(renders, "%s-run%d.exr" % (tag, run))
            cmd = vkpt_cmd(out) if variant is None else mitsuba_cmd(variant, out)
            if os.path.exists(out):
                os.remove(out)
            code, wall, peak, stdout, stderr = run_measured(cmd, os.path.join(renders, "%s-run%d" % (tag, run)),
                                                            args.timeout)
            row = {"wall_s": wall, "peak_mb": peak, "cmd": cmd}
            if code != 0 or not os.path.exists(out):
                row["error"] = failure_line(code, stdout, stderr)
            else:
                if variant is None:
                    parsed = parse_vkpt(stdout)
                    if parsed is None:
                        row["error"] = "no summary line in vkpt's output"
                    else:
                        row.update(parsed)
                    summary = [l for l in stdout.splitlines() if l.startswith(("device:", "rendered "))]
                    for line in summary + [l for l in stderr.splitlines() if l.startswith(("note", "warning"))]:
                        if line not in notes:
                            notes.append(line)
                else:
                    row.update(json.loads(stdout.strip().splitlines()[-1]))
                    row["samples_per_s"] = SIZE * SIZE * args.spp / row["render_s"]
                if "error" not in row:
                    row["mean"], row["se"] = image_stats(out, variant is None)
            results[label].append(row)
            print("  run %d %-20s %s" % (run + 1, label, describe(row)), flush=True)
    for label, why in skipped.items():
        results[label] = [{"skipped": why}]
    order = ["vkpt"] + ["Mitsuba " + v for v in args.mitsuba_variants.split(",") if v]
    results = {label: results[label] for label in order}
    return stem, desc, results, notes


def describe(row):
    if "error" in row:
        return "%.1f s, peak %.0f MB: FAILED %s" % (row["wall_s"], row["peak_mb"], row["error"])
    return "%.2f s whole, load %.2f s, build %.2f s, render %.2f s, %.0f samples/s, peak %.0f MB, mean %.5f" % (
        row["wall_s"], row["load_s"], row["build_s"], row["render_s"], row["samples_per_s"], row["peak_mb"],
        row["mean"])


def table(all_results, spp):
    lines = [
        "| scene | renderer | whole process s | load s | build s | render s | samples/s | peak MB | mean | mean / vkpt - 1 |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for stem, desc, results, _ in all_results:
        vkpt_ok = [r for r in results["vkpt"] if "error" not in r]
        vkpt_mean = median([r["mean"] for r in vkpt_ok]) if vkpt_ok else None
        vkpt_se = median([r["se"] for r in vkpt_ok if r.get("se")]) if any(r.get("se") for r in vkpt_ok) else None
        name = "%s (%s tris)" % (stem, short(desc["triangles"]))
        for label, rows in results.items():
            if "skipped" in rows[0]:
                lines.append("| %s | %s | | | | | | | | %s |" % (name, label, rows[0]["skipped"]))
                continue
            ok = [r for r in rows if "error" not in r]
            if not ok:
                err = rows[-1]["error"].replace("|", "/")
                lines.append("| %s | %s | %.1f | | | | | %.0f | | FAILED: %s |" % (
                    name, label, median([r["wall_s"] for r in rows]), median([r["peak_mb"] for r in rows]), err))
                continue
            m = {k: median([r[k] for r in ok]) for k in ["wall_s", "load_s", "build_s", "render_s",
                                                          "samples_per_s", "peak_mb", "mean"]}
            if label == "vkpt" or vkpt_mean is None:
                versus = "" if label == "vkpt" else "(no vkpt image)"
            else:
                rel = m["mean"] / vkpt_mean - 1.0
                z = ", z %+.1f" % ((m["mean"] - vkpt_mean) / (vkpt_se * 2 ** 0.5)) if vkpt_se else ""
                versus = "%+.2f %%%s" % (100 * rel, z)
            failed = len(rows) - len(ok)
            if failed:
                versus += " (%d of %d runs failed)" % (failed, len(rows))
            lines.append("| %s | %s | %.2f | %.2f | %.2f | %.2f | %s | %.0f | %.5f | %s |" % (
                name, label, m["wall_s"], m["load_s"], m["build_s"], m["render_s"], short(m["samples_per_s"]),
                m["peak_mb"], m["mean"], versus))
    return "\n".join(lines)


def short(x):
    for div, unit in [(1e9, "G"), (1e6, "M"), (1e3, "k")]:
        if x >= div:
            return "%.3g %s" % (x / div, unit)
    return "%.3g" % x


def main():
    if len(sys.argv) == 6 and sys.argv[1] == "--mitsuba-child":
        mitsuba_child(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5])
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default=DEFAULT_SCENES, help="comma-separated glTF names in --out, without .gltf")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--runs", type=int, default=1, help="rounds of renders taking turns (medians reported)")
    ap.add_argument("--vkpt-args", default="", help="more vkpt flags, after the defaults (e.g. \"--device vulkan\")")
    ap.add_argument("--mitsuba-variants", default="llvm_ad_rgb,scalar_rgb", help="comma-separated Mitsuba variants")
    ap.add_argument("--llvm-max-instances", type=int, default=1000,
                    help="skip Mitsuba's llvm variants on scenes with more instances (default 1000)")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "large-scenes"))
    ap.add_argument("--vkpt", default=os.path.join(ROOT, "target", "release", "vkpt"))
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds before a render process is killed")
    args = ap.parse_args()
    if not os.path.exists(args.vkpt):
        sys.exit("%s not found: cargo build --release" % args.vkpt)
    choose_libllvm()  # before Dr.Jit is imported
    ensure_mitsuba()
    args.out = os.path.abspath(args.out)
    me = os.path.abspath(__file__)
    started = time.perf_counter()
    all_results = [bench_scene(args, stem, me) for stem in args.scenes.split(",") if stem]

    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    cpu = ""
    if os.path.exists("/proc/cpuinfo"):
        with open("/proc/cpuinfo") as f:
            cpu = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "")
    head = ["# vkpt and Mitsuba 3 on large scenes", "",
            "`python3 benches/mitsuba_large.py %s` at vkpt %s; %s, %d cores, %s; %dx%d, %d spp, median of %d run%s." % (
                " ".join(shlex.quote(a) for a in sys.argv[1:]), commit.stdout.strip() or "?", cpu,
                os.cpu_count() or 0, platform.platform(terse=True), SIZE, SIZE, args.spp, args.runs,
                "" if args.runs == 1 else "s"),
            "",
            "load: vkpt's glTF read (instances flattened), Mitsuba's Python start-up and import; build: vkpt's "
            "BVH, Mitsuba's load_dict (PLY read and Embree BVH); peak MB: the process's maximum resident set.",
            "", ""]
    body = table(all_results, args.spp)
    notes = []
    for stem, _, _, scene_notes in all_results:
        notes += ["- %s: %s" % (stem, n) for n in scene_notes]
    text = "\n".join(head) + body + "\n" + ("\nvkpt's summary and notes:\n\n" + "\n".join(notes) + "\n" if notes else "")
    print("\n" + text)
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write(text)
    print("wrote %s (%.0f s in all)" % (os.path.join(args.out, "results.md"), time.perf_counter() - started))


if __name__ == "__main__":
    main()
