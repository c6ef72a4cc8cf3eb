#!/usr/bin/env python3
"""Large glTF 2.0 scenes for benchmarks (never CI): many triangles, many
instances, EXT_mesh_gpu_instancing. Each is a `.gltf` (JSON) plus one `.bin`
(little-endian) written into --out (default target/large-scenes/, never
committed). Deterministic: fixed seeds, same bytes on every run.

    python3 benches/large_scenes.py                      # the default scenes
    python3 benches/large_scenes.py --scenes instances-100,forest-10k
    python3 benches/large_scenes.py --triangles 1310720  # also bumpy-1310720
    python3 benches/large_scenes.py --flatten            # also the *-flat.gltf twins

Standard library only (no numpy needed): on this project's 2-core machine
bumpy-5m took 13 s to write, instances-100-flat (786 MB) 86 s. benches/mitsuba_large.py renders these scenes with vkpt and
Mitsuba 3 side by side (and writes the ones it needs).

Every scene is a closed room of Lambertian walls (white floor, ceiling,
back and front walls, red wall at +X, green at -X) lit by one one-sided
emissive quad on the ceiling facing down (emissiveFactor times
KHR_materials_emissive_strength), seen by a perspective camera inside the
room. The materials are exactly Lambertian (KHR_materials_specular
specularFactor 0, as scenes/generate.py's Cornell box).

Scenes (--scenes, comma-separated):

    bumpy-5m        one "bumpy" sphere of 5,000,000 triangles, white, in a
                    room of the Cornell box's size and camera (0.278, 0.273,
                    -0.8) looking down +Z, vertical fov 39.3077 degrees; the
                    room is closed by a front wall behind the camera.
    bumpy-N         the same with at least N triangles (N may end in k or m:
                    bumpy-1.31m, bumpy-32k, bumpy-1310720); --triangles N
                    adds bumpy-N to the list.
    instances-100   100 nodes (a 10 x 10 grid in the same room, each with
                    its own rotation and uniform scale; three mirrored by a
                    negative scale on X, one scaled non-uniformly) all
                    referencing ONE bumpy sphere mesh of 327,680 triangles:
                    32,768,000 triangles once instanced.
    forest-10k      10,000 trees (a cone on a cylinder, 288 triangles, two
                    materials: green canopy, brown trunk) on the floor of a
                    12 x 12 x 5 m room, seen from above at an angle. Written
                    twice: forest-10k-nodes.gltf (10,000 nodes referencing
                    one mesh) and forest-10k-gpu-instancing.gltf (one node
                    with EXT_mesh_gpu_instancing: TRANSLATION, ROTATION (unit
                    quaternions) and SCALE float accessors; the extension is
                    in extensionsUsed, not extensionsRequired, so a loader
                    without it shows one tree at the node's own transform,
                    the identity, at the room's centre). Both hold the same
                    float32 transforms.

The bumpy sphere is a geodesic icosphere of frequency f (each icosahedron
face cut into f^2 triangles, 20 f^2 in all, f the smallest giving at least
the asked count: f = 500 gives exactly 5,000,000, f = 256 gives 1,310,720,
f = 128 gives 327,680) whose vertices are pushed out along the radius by a
sum of four sine waves (amplitude 4 % of the radius), with smooth normals
from the displacement's analytic gradient: n ~ (1 + h) u - grad_S h. Its
mesh has radius about 1 around the origin; the node's transform places it.

--flatten also writes, for every scene, NAME-flat.gltf: every instance's
triangles transformed into world space (positions by the node's matrix,
normals by its inverse transpose, winding reversed where the determinant
is negative, as glTF says a mirrored node's faces turn) and merged into one
mesh per material, nodes without transforms: the triangles a flattening
loader makes, for comparing renders of instanced and flattened files image
for image. instances-100-flat.gltf is about 0.8 GB.

Printed per scene: file, unique triangles (stored in the file), instances
(mesh instances: nodes, or rows of EXT_mesh_gpu_instancing), instanced
triangles (what is in the world), file size (.gltf plus .bin) and seconds
to write.
"""

import argparse
import json
import math
import os
import random
import re
import struct
import sys
import time
from array import array

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scenes"))
import generate  # noqa: E402  (the Cornell box's materials and sizes)

DEFAULT_SCENES = ["bumpy-5m", "instances-100", "forest-10k"]
if sys.byteorder != "little" or array("I").itemsize != 4 or array("f").itemsize != 4:
    sys.exit("large_scenes.py writes the arrays' bytes as they are: it needs a little-endian machine "
             "with 4-byte array('I') and array('f')")

# Reflectances (the Cornell box's, scenes/generate.py) and the light's
# radiance; the forest's light is larger and farther, hence dimmer.
WHITE = [0.725, 0.71, 0.68]
RED = [0.63, 0.065, 0.05]
GREEN = [0.14, 0.45, 0.091]
LIGHT_BASE = [0.78, 0.78, 0.78]
SPHERE = [0.8, 0.8, 0.8]
CANOPY = [0.12, 0.38, 0.08]
TRUNK = [0.35, 0.2, 0.09]
EMISSION = [17.0, 12.0, 4.0]
FOREST_EMISSION = [4.25, 3.0, 1.0]


# --------------------------------------------------------------------------
# A glTF document with one external .bin, written as it grows.

class Writer:
    """Appends arrays to NAME.bin as they come (so a flattened scene never
    has to sit in memory whole) and collects the JSON."""

    def __init__(self, folder, name, generator_note):
        self.folder, self.name = folder, name
        self.bin_path = os.path.join(folder, name + ".bin")
        self.bin = open(self.bin_path + ".part", "wb")
        self.size = 0
        self.gltf = {
            "asset": {"version": "2.0", "generator": "vkpt benches/large_scenes.py (%s)" % generator_note},
            "extensionsUsed": [],
            "scene": 0,
            "scenes": [],
            "nodes": [],
            "cameras": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }
        self.unique_triangles = 0

    def use(self, extension):
        if extension not in self.gltf["extensionsUsed"]:
            self.gltf["extensionsUsed"].append(extension)

    def begin_view(self):
        pad = (-self.size) % 4
        if pad:
            self.bin.write(b"\0" * pad)
            self.size += pad
        return self.size

    def write(self, arr):
        """Appends a typed array's bytes (little-endian: checked above)."""
        arr.tofile(self.bin)
        self.size += len(arr) * arr.itemsize

    def end_view(self, start, target):
        view = {"buffer": 0, "byteOffset": start, "byteLength": self.size - start}
        if target is not None:
            view["target"] = target
        self.gltf["bufferViews"].append(view)
        return len(self.gltf["bufferViews"]) - 1

    def accessor(self, view, component, count, kind, bounds=None):
        acc = {"bufferView": view, "componentType": component, "count": count, "type": kind}
        if bounds:
            acc["min"], acc["max"] = bounds
        self.gltf["accessors"].append(acc)
        return len(self.gltf["accessors"]) - 1

    def vec_accessor(self, floats, kind, target, bounds=False):
        """A float VEC3/VEC4 accessor of one bufferView from array('f')."""
        width = {"VEC3": 3, "VEC4": 4}[kind]
        start = self.begin_view()
        self.write(floats)
        view = self.end_view(start, target)
        return self.accessor(view, 5126, len(floats) // width, kind, vec3_bounds(floats) if bounds else None)

    def primitive(self, positions, normals, indices, material):
        """Positions and normals (array('f'), xyz each), indices
        (array('I')): one indexed triangle-list primitive."""
        self.unique_triangles += len(indices) // 3
        return {
            "attributes": {
                "POSITION": self.vec_accessor(positions, "VEC3", 34962, bounds=True),
                "NORMAL": self.vec_accessor(normals, "VEC3", 34962),
            },
            "indices": self.index_accessor(indices),
            "material": material,
            "mode": 4,
        }

    def index_accessor(self, indices):
        start = self.begin_view()
        self.write(indices)
        return self.accessor(self.end_view(start, 34963), 5125, len(indices), "SCALAR")

    def mesh(self, name, primitives):
        self.gltf["meshes"].append({"name": name, "primitives": primitives})
        return len(self.gltf["meshes"]) - 1

    def material(self, m):
        for ext in m.get("extensions", {}):
            self.use(ext)
        self.gltf["materials"].append(m)
        return len(self.gltf["materials"]) - 1

    def node(self, node):
        self.gltf["nodes"].append(node)
        return len(self.gltf["nodes"]) - 1

    def finish(self, root_nodes, scene_name):
        self.begin_view()
        self.bin.close()
        os.replace(self.bin_path + ".part", self.bin_path)
        self.gltf["buffers"].append({"byteLength": self.size, "uri": self.name + ".bin"})
        self.gltf["scenes"].append({"name": scene_name, "nodes": root_nodes})
        for key in ["extensionsUsed", "cameras"]:
            if not self.gltf[key]:
                del self.gltf[key]
        path = os.path.join(self.folder, self.name + ".gltf")
        with open(path + ".part", "w", encoding="utf-8", newline="\n") as f:
            json.dump(self.gltf, f, indent=None, separators=(",", ":"))
            f.write("\n")
        os.replace(path + ".part", path)
        return path


def vec3_bounds(floats):
    """min and max of the float32 values stored, per component."""
    return ([min(floats[i::3]) for i in range(3)], [max(floats[i::3]) for i in range(3)])


def f32(x):
    """x rounded to float32, as a Python float."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def materials(w, names):
    """Lambertian materials by name (the light's is emissive), their indices."""
    colours = {"white": WHITE, "red": RED, "green": GREEN, "sphere": SPHERE, "canopy": CANOPY,
               "trunk": TRUNK, "ground": WHITE}
    out = {}
    for name in names:
        if name in ("light", "forest light"):
            m = generate.lambert(name, LIGHT_BASE)
            emission = EMISSION if name == "light" else FOREST_EMISSION
            strength = max(emission)
            m["emissiveFactor"] = [e / strength for e in emission]
            m["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": strength}
            m["doubleSided"] = False
        else:
            m = generate.lambert(name, colours[name])
        out[name] = w.material(m)
    return out


# --------------------------------------------------------------------------
# Geometry: quads, the room, the bumpy geodesic sphere, the tree.

def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(a):
    n = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    return [a[0] / n, a[1] / n, a[2] / n]


class Soup:
    """Flat-shaded triangles gathered per material (the room's walls)."""

    def __init__(self):
        self.parts = {}

    def quad(self, material, corners, facing):
        """Two triangles of a planar quad (corners in order around it),
        wound counter-clockwise seen from the side `facing` points to."""
        n = normalize(cross(sub(corners[1], corners[0]), sub(corners[2], corners[0])))
        if n[0] * facing[0] + n[1] * facing[1] + n[2] * facing[2] < 0.0:
            corners = [corners[0], corners[3], corners[2], corners[1]]
            n = [-n[0], -n[1], -n[2]]
        pos, nrm, idx = self.parts.setdefault(material, (array("f"), array("f"), array("I")))
        base = len(pos) // 3
        for p in corners:
            pos.extend(p)
            nrm.extend(n)
        idx.extend([base, base + 1, base + 2, base, base + 2, base + 3])


def room(soup, lo, hi, light_centre, light_half, light_material):
    """A closed box [lo, hi] of walls facing in (red at +X, green at -X,
    white elsewhere) and a light quad 0.1 mm below the ceiling facing down."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    c = [(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2]
    walls = [
        ("white", [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]]),  # floor
        ("white", [[x0, y1, z0], [x1, y1, z0], [x1, y1, z1], [x0, y1, z1]]),  # ceiling
        ("white", [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]]),  # back
        ("white", [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0]]),  # front (behind the camera)
        ("red", [[x1, y0, z0], [x1, y0, z1], [x1, y1, z1], [x1, y1, z0]]),
        ("green", [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]]),
    ]
    for material, q in walls:
        centre = [sum(p[i] for p in q) / 4 for i in range(3)]
        soup.quad(material, q, sub(c, centre))
    lx, ly, lz = light_centre
    hx, hz = light_half
    soup.quad(light_material, [[lx - hx, ly, lz - hz], [lx + hx, ly, lz - hz], [lx + hx, ly, lz + hz],
                               [lx - hx, ly, lz + hz]], [0.0, -1.0, 0.0])


def icosahedron():
    """Unit icosahedron: 12 corners, 20 faces wound outward (CCW)."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [normalize(v) for v in [
        [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
        [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
    ]]
    faces = [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
        [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
        [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ]
    out = []
    for a, b, c in faces:
        n = cross(sub(verts[b], verts[a]), sub(verts[c], verts[a]))
        centre = [verts[a][i] + verts[b][i] + verts[c][i] for i in range(3)]
        out.append([a, b, c] if sum(n[i] * centre[i] for i in range(3)) > 0 else [a, c, b])
    return verts, out


def frequency_for(triangles):
    """The smallest geodesic frequency f with 20 f^2 >= triangles."""
    f = max(1, math.isqrt(max(0, (triangles + 19) // 20)))
    while 20 * f * f < triangles:
        f += 1
    return f


def geodesic_directions(f):
    """Unit directions (lists xs, ys, zs) and triangle indices (array('I'))
    of a frequency-f geodesic sphere: 10 f^2 + 2 vertices, 20 f^2
    triangles, every vertex stored once (corners, then f-1 per edge, then
    each face's interior)."""
    corners, faces = icosahedron()
    xs, ys, zs = [], [], []

    def add_point(p):
        n = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
        xs.append(p[0] / n)
        ys.append(p[1] / n)
        zs.append(p[2] / n)

    for p in corners:
        add_point(p)
    edges = {}
    for face in faces:
        for k in range(3):
            a, b = face[k], face[(k + 1) % 3]
            key = (min(a, b), max(a, b))
            if key in edges:
                continue
            edges[key] = len(xs)
            lo, hi = corners[key[0]], corners[key[1]]
            for t in range(1, f):
                s = t / f
                add_point([lo[i] + (hi[i] - lo[i]) * s for i in range(3)])

    def edge_run(a, b):
        """The f-1 vertices strictly between corners a and b, from a."""
        base = edges[(min(a, b), max(a, b))]
        run = list(range(base, base + f - 1))
        return run if a < b else run[::-1]

    indices = array("I")
    for a, b, c in faces:
        A, B, C = corners[a], corners[b], corners[c]
        ab, ac, bc = edge_run(a, b), edge_run(a, c), edge_run(b, c)
        # Row j (0..f) holds the grid points i = 0..f-j of A + (B-A) i/f + (C-A) j/f.
        rows = [[a] + ab + [b]]
        for j in range(1, f):
            first = len(xs)
            for i in range(1, f - j):
                add_point([A[k] + (B[k] - A[k]) * i / f + (C[k] - A[k]) * j / f for k in range(3)])
            rows.append([ac[j - 1]] + list(range(first, len(xs))) + [bc[j - 1]])
        rows.append([c])
        for j in range(f):
            r, s = rows[j], rows[j + 1]
            n = len(r)
            up = [0] * (3 * (n - 1))
            up[0::3], up[1::3], up[2::3] = r[:-1], r[1:], s
            indices.extend(up)
            if n > 2:
                down = [0] * (3 * (n - 2))
                down[0::3], down[1::3], down[2::3] = r[1:-1], s[1:], s[:-1]
                indices.extend(down)
    assert len(xs) == 10 * f * f + 2 and len(indices) == 60 * f * f
    return xs, ys, zs, indices


# h(u) = AMPLITUDE * sum_k a_k sin(w_k . u + phase_k), fixed waves.
AMPLITUDE = 0.04


def bump_waves():
    rng = random.Random(20240917)
    waves = []
    for k in range(4):
        d = normalize([rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1)])
        freq = [7.0, 11.0, 17.0, 23.0][k]
        waves.append(([freq * c for c in d], rng.uniform(0, 2 * math.pi), [0.45, 0.3, 0.15, 0.1][k]))
    return waves


def bumpy_sphere(triangles):
    """A bumpy geodesic sphere of radius about 1 with at least `triangles`
    triangles: positions, normals (array('f')), indices (array('I'))."""
    xs, ys, zs, indices = geodesic_directions(frequency_for(triangles))
    (w0, p0, a0), (w1, p1, a1), (w2, p2, a2), (w3, p3, a3) = bump_waves()
    a0, a1, a2, a3 = (AMPLITUDE * a for a in (a0, a1, a2, a3))
    positions = array("f", bytes(12 * len(xs)))
    normals = array("f", bytes(12 * len(xs)))
    sin, cos, sqrt = math.sin, math.cos, math.sqrt
    o = 0
    for x, y, z in zip(xs, ys, zs):
        t0 = w0[0] * x + w0[1] * y + w0[2] * z + p0
        t1 = w1[0] * x + w1[1] * y + w1[2] * z + p1
        t2 = w2[0] * x + w2[1] * y + w2[2] * z + p2
        t3 = w3[0] * x + w3[1] * y + w3[2] * z + p3
        r = 1.0 + a0 * sin(t0) + a1 * sin(t1) + a2 * sin(t2) + a3 * sin(t3)
        c0, c1, c2, c3 = a0 * cos(t0), a1 * cos(t1), a2 * cos(t2), a3 * cos(t3)
        gx = c0 * w0[0] + c1 * w1[0] + c2 * w2[0] + c3 * w3[0]
        gy = c0 * w0[1] + c1 * w1[1] + c2 * w2[1] + c3 * w3[1]
        gz = c0 * w0[2] + c1 * w1[2] + c2 * w2[2] + c3 * w3[2]
        # Surface gradient (tangential part); n ~ r u - grad_S h.
        gu = gx * x + gy * y + gz * z
        nx, ny, nz = r * x - (gx - gu * x), r * y - (gy - gu * y), r * z - (gz - gu * z)
        inv = 1.0 / sqrt(nx * nx + ny * ny + nz * nz)
        positions[o], positions[o + 1], positions[o + 2] = r * x, r * y, r * z
        normals[o], normals[o + 1], normals[o + 2] = nx * inv, ny * inv, nz * inv
        o += 3
    return positions, normals, indices


def tree():
    """A tree of 288 triangles around +Y with its base at the origin:
    canopy (a cone of 96 segments with its base disk) and trunk (a closed
    cylinder of 24 segments). {material: (positions, normals, indices)}."""
    out = {}
    # Canopy: base radius 0.5 at y 0.3, apex at y 1.6; smooth sides (one
    # apex vertex per segment, its normal half-way between the segment's).
    pos, nrm, idx = array("f"), array("f"), array("I")
    seg, r, y0, y1 = 96, 0.5, 0.3, 1.6
    slope = r / (y1 - y0)
    k = 1.0 / math.sqrt(1.0 + slope * slope)
    for i in range(seg + 1):
        a = 2 * math.pi * i / seg
        pos.extend([r * math.cos(a), y0, -r * math.sin(a)])
        nrm.extend([k * math.cos(a), k * slope, -k * math.sin(a)])
    for i in range(seg):
        a = 2 * math.pi * (i + 0.5) / seg
        pos.extend([0.0, y1, 0.0])
        nrm.extend([k * math.cos(a), k * slope, -k * math.sin(a)])
    for i in range(seg):
        idx.extend([i, i + 1, seg + 1 + i])  # counter-clockwise seen from outside
    base = len(pos) // 3
    pos.extend([0.0, y0, 0.0])
    nrm.extend([0.0, -1.0, 0.0])
    for i in range(seg + 1):
        a = 2 * math.pi * i / seg
        pos.extend([r * math.cos(a), y0, -r * math.sin(a)])
        nrm.extend([0.0, -1.0, 0.0])
    for i in range(seg):
        idx.extend([base, base + 2 + i, base + 1 + i])  # facing down
    out["canopy"] = (pos, nrm, idx)
    # Trunk: radius 0.08 from y 0 to 0.35 (into the canopy), closed.
    pos, nrm, idx = array("f"), array("f"), array("I")
    seg, r, h = 24, 0.08, 0.35
    for i in range(seg + 1):
        a = 2 * math.pi * i / seg
        c, s = math.cos(a), -math.sin(a)
        pos.extend([r * c, 0.0, r * s, r * c, h, r * s])
        nrm.extend([c, 0.0, s, c, 0.0, s])
    for i in range(seg):
        b, t, b2, t2 = 2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3
        idx.extend([b, b2, t, t, b2, t2])
    for y, ny in [(0.0, -1.0), (h, 1.0)]:
        base = len(pos) // 3
        pos.extend([0.0, y, 0.0])
        nrm.extend([0.0, ny, 0.0])
        for i in range(seg + 1):
            a = 2 * math.pi * i / seg
            pos.extend([r * math.cos(a), y, -r * math.sin(a)])
            nrm.extend([0.0, ny, 0.0])
        for i in range(seg):
            if ny > 0:
                idx.extend([base, base + 1 + i, base + 2 + i])
            else:
                idx.extend([base, base + 2 + i, base + 1 + i])
    out["trunk"] = (pos, nrm, idx)
    return out


# --------------------------------------------------------------------------
# Transforms: glTF TRS (rotation a unit quaternion x, y, z, w).

def quat_about(axis, angle):
    axis = normalize(axis)
    s = math.sin(angle / 2)
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)]


def random_quat(rng):
    """A uniformly random unit quaternion (Shoemake)."""
    u1, u2, u3 = rng.random(), rng.random(), rng.random()
    a, b = math.sqrt(1 - u1), math.sqrt(u1)
    return [a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2),
            b * math.sin(2 * math.pi * u3), b * math.cos(2 * math.pi * u3)]


def unit_f32_quat(q):
    n = math.sqrt(sum(c * c for c in q))
    return [f32(c / n) for c in q]


def trs_matrix(t, q, s):
    """Rows of the 3x4 matrix T R S."""
    x, y, z, w = q
    r = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return [[r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]] for i in range(3)]


def transform_into(m, positions, normals, indices, base, out_pos, out_nrm, out_idx):
    """Appends a mesh transformed by the 3x4 matrix m: positions by m,
    normals by its inverse transpose (renormalized), indices offset by
    base, winding reversed where det(m) < 0."""
    (a, b, c, tx), (d, e, f, ty), (g, h, i, tz) = m
    px, py, pz = positions[0::3], positions[1::3], positions[2::3]
    n = len(px)
    out = [0.0] * (3 * n)
    out[0::3] = [a * x + b * y + c * z + tx for x, y, z in zip(px, py, pz)]
    out[1::3] = [d * x + e * y + f * z + ty for x, y, z in zip(px, py, pz)]
    out[2::3] = [g * x + h * y + i * z + tz for x, y, z in zip(px, py, pz)]
    out_pos.extend(out)
    # Cofactor matrix = det * inverse transpose: the same directions.
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    sign = 1.0 if det > 0 else -1.0
    ca, cb, cc = (e * i - f * h) * sign, -(d * i - f * g) * sign, (d * h - e * g) * sign
    cd, ce, cf = -(b * i - c * h) * sign, (a * i - c * g) * sign, -(a * h - b * g) * sign
    cg, ch, ci = (b * f - c * e) * sign, -(a * f - c * d) * sign, (a * e - b * d) * sign
    nx, ny, nz = normals[0::3], normals[1::3], normals[2::3]
    wx = [ca * x + cb * y + cc * z for x, y, z in zip(nx, ny, nz)]
    wy = [cd * x + ce * y + cf * z for x, y, z in zip(nx, ny, nz)]
    wz = [cg * x + ch * y + ci * z for x, y, z in zip(nx, ny, nz)]
    inv = [1.0 / math.sqrt(x * x + y * y + z * z) for x, y, z in zip(wx, wy, wz)]
    out[0::3] = [x * k for x, k in zip(wx, inv)]
    out[1::3] = [y * k for y, k in zip(wy, inv)]
    out[2::3] = [z * k for z, k in zip(wz, inv)]
    out_nrm.extend(out)
    if det > 0:
        out_idx.extend([j + base for j in indices])
    else:
        flipped = [0] * len(indices)
        flipped[0::3], flipped[1::3], flipped[2::3] = indices[0::3], indices[2::3], indices[1::3]
        out_idx.extend([j + base for j in flipped])


# --------------------------------------------------------------------------
# Scenes: geometry once, then written instanced or flattened.

class Scene:
    """What a scene holds, independent of how it is written: the room's
    soup, unique meshes {name: {material: (positions, normals, indices)}},
    instances [(mesh name, translation, rotation, scale)], a camera."""

    def __init__(self, name):
        self.name = name
        self.soup = Soup()
        self.meshes = {}
        self.instances = []
        self.camera = None  # (yfov radians, translation, rotation)
        self.materials = []


def cornell_room(scene):
    """The Cornell box's room (0.556 x 0.549 x 0.559 m, light 130 x 105 mm),
    closed by a front wall at z = -0.85 just behind the Cornell camera."""
    room(scene.soup, [0.0, 0.0, -0.85], [0.556, 0.5488, 0.5592], [0.278, 0.5487, 0.2795], [0.065, 0.0525],
         "light")
    scene.camera = (math.radians(39.3077), [0.278, 0.273, -0.8], [0.0, 1.0, 0.0, 0.0])
    scene.materials = ["white", "red", "green", "light"]


def parse_count(text):
    """5m -> 5000000, 1.31m -> 1310000, 32k -> 32000, 1310720 -> 1310720."""
    m = re.fullmatch(r"([0-9]+(?:\.[0-9]+)?)([kKmM]?)", text)
    if not m:
        raise ValueError(text)
    return int(round(float(m.group(1)) * {"": 1, "k": 1e3, "m": 1e6}[m.group(2).lower()]))


def bumpy_scene(name, triangles):
    s = Scene(name)
    cornell_room(s)
    s.materials.append("sphere")
    pos, nrm, idx = bumpy_sphere(triangles)
    s.meshes["bumpy sphere"] = {"sphere": (pos, nrm, idx)}
    # Radius 0.16 m, resting near the floor in the middle of the room.
    s.instances.append(("bumpy sphere", [0.278, 0.18, 0.28], [0.0, 0.0, 0.0, 1.0], [0.16, 0.16, 0.16]))
    return s


def instances_scene(name):
    s = Scene(name)
    cornell_room(s)
    s.materials.append("sphere")
    s.meshes["bumpy sphere"] = {"sphere": bumpy_sphere(327680)}
    rng = random.Random(100)
    for row in range(10):
        for col in range(10):
            k = 10 * row + col
            # A 10 x 10 wall of spheres across the room, 5 cm apart.
            t = [0.053 + 0.05 * col, 0.045 + 0.05 * row, 0.30 + rng.uniform(-0.08, 0.08)]
            q = random_quat(rng)
            r = 0.016 * rng.uniform(0.75, 1.25)
            scale = [r, r, r]
            if k in (7, 42, 86):
                scale = [-r, r, r]  # mirrored
            if k == 55:
                scale = [1.4 * r, 0.6 * r, r]  # non-uniform
            s.instances.append(("bumpy sphere", [f32(c) for c in t], unit_f32_quat(q), [f32(c) for c in scale]))
    return s


def forest_scene(name, count=10000):
    s = Scene(name)
    half, height = 6.0, 5.0
    room(s.soup, [-half, 0.0, -half], [half, height, half], [0.0, height - 0.0001, 0.0], [1.5, 1.5],
         "forest light")
    s.materials = ["white", "red", "green", "forest light", "canopy", "trunk"]
    s.meshes["tree"] = tree()
    rng = random.Random(10000)
    side = int(math.ceil(math.sqrt(count)))
    spacing = 10.0 / side
    for k in range(count):
        row, col = divmod(k, side)
        t = [-5.0 + spacing * (col + 0.5 + rng.uniform(-0.3, 0.3)), 0.0,
             -5.0 + spacing * (row + 0.5 + rng.uniform(-0.3, 0.3))]
        # Turned about +Y, leaning a little.
        q = quat_about([0.0, 1.0, 0.0], rng.uniform(0, 2 * math.pi))
        lean = quat_about([rng.uniform(-1, 1), 0.0, rng.uniform(-1, 1)], rng.uniform(0, 0.12))
        q = quat_mul(lean, q)
        size = spacing * rng.uniform(0.8, 1.3)
        scale = [size, size * rng.uniform(0.8, 1.6), size]
        s.instances.append(("tree", [f32(c) for c in t], unit_f32_quat(q), [f32(c) for c in scale]))
    # Above the front of the forest, looking down at about 35 degrees.
    pitch = math.radians(-35.0)
    s.camera = (math.radians(55.0), [0.0, 3.4, 5.6], quat_about([1.0, 0.0, 0.0], pitch))
    return s


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def begin(scene, folder, file_name, note):
    w = Writer(folder, file_name, note)
    mats = materials(w, scene.materials)
    roots = []
    prims = [w.primitive(p, n, i, mats[m]) for m, (p, n, i) in scene.soup.parts.items()]
    roots.append(w.node({"name": "room", "mesh": w.mesh("room", prims)}))
    yfov, t, q = scene.camera
    w.gltf["cameras"].append({"name": "main", "type": "perspective",
                              "perspective": {"yfov": yfov, "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0}})
    roots.append(w.node({"name": "camera", "camera": 0, "translation": t, "rotation": q}))
    return w, mats, roots


def write_instanced(scene, folder, file_name, gpu_instancing=False):
    """Unique meshes once; instances as nodes (or EXT_mesh_gpu_instancing)."""
    w, mats, roots = begin(scene, folder, file_name, "gpu instancing" if gpu_instancing else "nodes")
    mesh_ids = {}
    for mesh_name, parts in scene.meshes.items():
        prims = [w.primitive(p, n, i, mats[m]) for m, (p, n, i) in parts.items()]
        mesh_ids[mesh_name] = w.mesh(mesh_name, prims)
    if gpu_instancing:
        for mesh_name in scene.meshes:
            rows = [inst for inst in scene.instances if inst[0] == mesh_name]
            attrs = {}
            for key, kind, column in [("TRANSLATION", "VEC3", 1), ("ROTATION", "VEC4", 2), ("SCALE", "VEC3", 3)]:
                attrs[key] = w.vec_accessor(array("f", [c for inst in rows for c in inst[column]]), kind, None)
            w.use("EXT_mesh_gpu_instancing")
            roots.append(w.node({"name": mesh_name + " instances", "mesh": mesh_ids[mesh_name],
                                 "extensions": {"EXT_mesh_gpu_instancing": {"attributes": attrs}}}))
    else:
        for k, (mesh_name, t, q, s) in enumerate(scene.instances):
            roots.append(w.node({"name": "%s %d" % (mesh_name, k), "mesh": mesh_ids[mesh_name],
                                 "translation": t, "rotation": q, "scale": s}))
    return w.finish(roots, file_name)


def write_flattened(scene, folder, file_name):
    """Every instance's triangles in world space, one mesh per material."""
    w, mats, roots = begin(scene, folder, file_name, "flattened")
    by_material = {}
    for mesh_name, t, q, s in scene.instances:
        for m in scene.meshes[mesh_name]:
            by_material.setdefault(m, []).append((mesh_name, trs_matrix(t, q, s)))
    prims = []
    for m, items in by_material.items():
        # Positions stream to the .bin instance by instance; normals and
        # indices wait in memory (written right after, each a view).
        start = w.begin_view()
        normals, indices = array("f"), array("I")
        lo, hi = [math.inf] * 3, [-math.inf] * 3
        vertices = 0
        for mesh_name, mat in items:
            p, n, i = scene.meshes[mesh_name][m]
            pos = array("f")
            transform_into(mat, p, n, i, vertices, pos, normals, indices)
            vertices += len(p) // 3
            b_lo, b_hi = vec3_bounds(pos)
            lo = [min(a, b) for a, b in zip(lo, b_lo)]
            hi = [max(a, b) for a, b in zip(hi, b_hi)]
            w.write(pos)
        pos_acc = w.accessor(w.end_view(start, 34962), 5126, vertices, "VEC3", (lo, hi))
        nrm_acc = w.vec_accessor(normals, "VEC3", 34962)
        del normals
        w.unique_triangles += len(indices) // 3
        prims.append({"attributes": {"POSITION": pos_acc, "NORMAL": nrm_acc},
                      "indices": w.index_accessor(indices), "material": mats[m], "mode": 4})
        del indices
    roots.append(w.node({"name": "flattened", "mesh": w.mesh("flattened", prims)}))
    return w.finish(roots, file_name)


# --------------------------------------------------------------------------
# Reading back: the checks every written file passes.

def validate(path):
    """Buffer length, views inside the buffer, accessors inside their views,
    POSITION min/max present, index values below the vertex count (checked
    on the maximum, read in chunks). Returns (unique triangles, mesh
    instances, instanced triangles), the room's walls and light (14
    triangles) left out of all three."""
    with open(path) as f:
        g = json.load(f)
    folder = os.path.dirname(path)
    buf = g["buffers"][0]
    bin_path = os.path.join(folder, buf["uri"])
    assert os.path.getsize(bin_path) == buf["byteLength"], "buffer byteLength"
    for v in g["bufferViews"]:
        assert v["byteOffset"] % 4 == 0 and v["byteOffset"] + v["byteLength"] <= buf["byteLength"]
    size = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}
    for a in g["accessors"]:
        v = g["bufferViews"][a["bufferView"]]
        assert a.get("byteOffset", 0) + a["count"] * 4 * size[a["type"]] <= v["byteLength"], "accessor fits"
    mesh_tris = []
    with open(bin_path, "rb") as f:
        for mesh in g["meshes"]:
            tris = 0
            for p in mesh["primitives"]:
                pa = g["accessors"][p["attributes"]["POSITION"]]
                assert "min" in pa and "max" in pa, "POSITION min/max"
                assert g["accessors"][p["attributes"]["NORMAL"]]["count"] == pa["count"]
                ia = g["accessors"][p["indices"]]
                assert ia["componentType"] == 5125 and ia["count"] % 3 == 0
                tris += ia["count"] // 3
                v = g["bufferViews"][ia["bufferView"]]
                f.seek(v["byteOffset"])
                left, top = ia["count"], 0
                while left:
                    chunk = array("I")
                    chunk.fromfile(f, min(left, 1 << 22))
                    left -= len(chunk)
                    top = max(top, max(chunk))
                assert top < pa["count"], "index out of range"
            mesh_tris.append(tris)
    instances = {}
    for node in g["nodes"]:
        if "mesh" not in node:
            continue
        ext = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
        n = g["accessors"][ext["attributes"]["TRANSLATION"]]["count"] if ext else 1
        instances[node["mesh"]] = instances.get(node["mesh"], 0) + n
    objects = {k: n for k, n in instances.items() if g["meshes"][k]["name"] != "room"}
    return (sum(mesh_tris[k] for k in objects), sum(objects.values()),
            sum(mesh_tris[k] * n for k, n in objects.items()))


# --------------------------------------------------------------------------

def build(name):
    """The Scene for a scene name, and the file names it is written as."""
    if name.startswith("bumpy-"):
        return bumpy_scene(name, parse_count(name[len("bumpy-"):])), [name]
    if name == "instances-100":
        return instances_scene(name), [name]
    if name == "forest-10k":
        return forest_scene(name), ["forest-10k-nodes", "forest-10k-gpu-instancing"]
    raise ValueError("unknown scene %r (known: bumpy-5m, bumpy-N, instances-100, forest-10k)" % name)


def files_of(name, flatten=False):
    """The .gltf file names (without folder) a scene name writes."""
    if name.startswith("bumpy-"):
        parse_count(name[len("bumpy-"):])
        names = [name]
    elif name == "instances-100":
        names = [name]
    elif name == "forest-10k":
        names = ["forest-10k-nodes", "forest-10k-gpu-instancing"]
    else:
        raise ValueError("unknown scene %r" % name)
    if flatten:
        names.append(name + "-flat")
    return [n + ".gltf" for n in names]


def write_scene(name, folder, flatten=False, quiet=False):
    """Writes a scene's files into folder; prints a line per file."""
    os.makedirs(folder, exist_ok=True)
    start = time.perf_counter()
    scene, names = build(name)
    geometry_s = time.perf_counter() - start
    outputs = []
    for file_name in names:
        t0 = time.perf_counter()
        path = write_instanced(scene, folder, file_name, gpu_instancing=file_name.endswith("gpu-instancing"))
        outputs.append((path, time.perf_counter() - t0 + geometry_s))
    if flatten:
        t0 = time.perf_counter()
        outputs.append((write_flattened(scene, folder, name + "-flat"), time.perf_counter() - t0 + geometry_s))
    for path, secs in outputs:
        unique, instances, world = validate(path)
        size = os.path.getsize(path) + os.path.getsize(path[:-len(".gltf")] + ".bin")
        if not quiet:
            print("%-52s %12s %9s %14s %9.1f MB %7.1f s" % (
                os.path.relpath(path), "{:,}".format(unique), "{:,}".format(instances), "{:,}".format(world),
                size / 1e6, secs), flush=True)
    return [p for p, _ in outputs]


def header():
    print("%-52s %12s %9s %14s %12s %9s" % ("file", "unique tris", "instances", "instanced tris", "size",
                                             "write"), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "large-scenes"))
    ap.add_argument("--scenes", default=",".join(DEFAULT_SCENES),
                    help="comma-separated: bumpy-5m, bumpy-N (N may end in k or m), instances-100, forest-10k")
    ap.add_argument("--triangles", type=int, action="append", default=[],
                    help="also write bumpy-N with at least N triangles (repeatable)")
    ap.add_argument("--flatten", action="store_true", help="also write each scene's NAME-flat.gltf")
    args = ap.parse_args()
    names = [s for s in args.scenes.split(",") if s] + ["bumpy-%d" % n for n in args.triangles]
    for name in names:
        try:
            files_of(name)
        except ValueError as e:
            sys.exit(str(e))
    header()
    for name in names:
        write_scene(name, args.out, args.flatten)


if __name__ == "__main__":
    main()
