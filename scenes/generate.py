#!/usr/bin/env python3
"""Writes vkpt's bundled scenes as glTF 2.0 files with embedded buffers.

    python3 scenes/generate.py        # writes every scene below into scenes/

Standard library only, deterministic (same bytes on every run). After
writing, each file is read back and checked: buffer byteLength matches the
decoded data, every accessor fits its buffer view, POSITION accessors have
min/max (the glTF spec requires them).

cornell-box.gltf: the Cornell University measured Cornell box
(https://www.graphics.cornell.edu/online/box/data.html), converted from
millimetres to metres, with the reflectances of the Mitsuba/pbrt "cbox" scene
and a light of emitted radiance (17, 12, 4). Walls face into the box, the
boxes face outward, the light faces down (-Y) and is single-sided.

white-furnace.gltf: a unit icosphere of albedo 0.8 inside a uniform
environment of radiance 1 (set by the vkpt scene extras). The sphere is
convex, so every reflected ray escapes: every pixel on it must converge to
exactly 0.8 and the background to 1 (the classic energy-conservation test).

furnace-glass-1.5.gltf, furnace-glass-0.67.gltf, furnace-mirror-0.8.gltf: the
same furnace with a smooth glass sphere (KHR_materials_transmission + volume,
KHR_materials_ior 1.5), an "air bubble" of relative IOR 0.67 (vkpt material
extras: glTF's IOR cannot go below 1) and a mirror of tint 0.8 (metallic 1,
roughness 0). The glass spheres must vanish (every pixel 1: Fresnel
reflection plus refraction, with radiance scaled by 1/eta^2 across the
interface, conserve energy); the mirror shows 0.8.

materials-showcase.gltf: the Cornell box (Lambertian walls: specularFactor
0) with every material path: a tinted mirror tall box (metallic 1, roughness
0), a smooth glass sphere (IOR 1.5) holding an air bubble (relative IOR
1/1.5), a normalized-Phong sphere (vkpt material extras) on the short box,
rough gold, rough red plastic, smooth blue plastic (delta specular over
diffuse), rough glass, absorbing green glass (KHR_materials_volume) on the
tall box, a frosted thin-walled sphere and a half-metal with a tinted
KHR_materials_specular layer.

materials-grid.gltf: the same material paths, one sphere each in a 4 x 3
grid filling a small frame (diffuse, Phong, tinted mirror, rough gold, rough
plastic, smooth plastic, glass holding an air bubble, rough glass, absorbing
glass, frosted thin-walled, tinted-specular half-metal, white rough metal)
before a striped wall, under an area light and a dim environment: the GPU
vs CPU comparison's scene, where each material covers many pixels.

furnace-rough-metal.gltf: the white furnace with a white rough metal
(metallic 1, roughness 1) on a finer icosphere: GGX single scattering
loses energy (multiple scattering between microfacets is not modelled), so
the sphere shows the directional albedo E(cos theta_o) that tests/furnace.rs
computes by quadrature.
"""

import base64
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


# --------------------------------------------------------------------------
# Small vector helpers.

def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def add(a, b):
    return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]


def scale(a, s):
    return [a[0] * s, a[1] * s, a[2] * s]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(a):
    n = math.sqrt(dot(a, a))
    return [a[0] / n, a[1] / n, a[2] / n]


def centroid(points):
    s = [0.0, 0.0, 0.0]
    for p in points:
        s = add(s, p)
    return scale(s, 1.0 / len(points))


# --------------------------------------------------------------------------
# A glTF document builder with one embedded buffer.

class Builder:
    def __init__(self):
        self.data = bytearray()
        self.gltf = {
            "asset": {"version": "2.0", "generator": "vkpt scenes/generate.py"},
            "scene": 0,
            "scenes": [],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }

    def _view(self, blob, target):
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(blob), "target": target}
        self.data.extend(blob)
        self.gltf["bufferViews"].append(view)
        return len(self.gltf["bufferViews"]) - 1

    def vec3_accessor(self, values, with_bounds):
        blob = b"".join(struct.pack("<3f", *v) for v in values)
        acc = {
            "bufferView": self._view(blob, 34962),
            "componentType": 5126,
            "count": len(values),
            "type": "VEC3",
        }
        if with_bounds:
            # Bounds of the float32 values actually stored.
            stored = [struct.unpack("<3f", struct.pack("<3f", *v)) for v in values]
            acc["min"] = [min(v[i] for v in stored) for i in range(3)]
            acc["max"] = [max(v[i] for v in stored) for i in range(3)]
        self.gltf["accessors"].append(acc)
        return len(self.gltf["accessors"]) - 1

    def index_accessor(self, indices):
        blob = b"".join(struct.pack("<H", i) for i in indices)
        acc = {
            "bufferView": self._view(blob, 34963),
            "componentType": 5123,
            "count": len(indices),
            "type": "SCALAR",
        }
        self.gltf["accessors"].append(acc)
        return len(self.gltf["accessors"]) - 1

    def material(self, m):
        used = self.gltf.setdefault("extensionsUsed", [])
        for ext in m.get("extensions", {}):
            if ext not in used:
                used.append(ext)
        self.gltf["materials"].append(m)
        return len(self.gltf["materials"]) - 1

    def mesh(self, name, positions, normals, material, indices=None):
        prim = {
            "attributes": {
                "POSITION": self.vec3_accessor(positions, True),
                "NORMAL": self.vec3_accessor(normals, False),
            },
            "material": material,
            "mode": 4,
        }
        if indices is not None:
            prim["indices"] = self.index_accessor(indices)
        self.gltf["meshes"].append({"name": name, "primitives": [prim]})
        return len(self.gltf["meshes"]) - 1

    def node(self, node):
        self.gltf["nodes"].append(node)
        return len(self.gltf["nodes"]) - 1

    def finish(self, path):
        if not self.gltf.get("extensionsUsed", True):
            del self.gltf["extensionsUsed"]
        self.gltf["buffers"].append({
            "byteLength": len(self.data),
            "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.data)).decode("ascii"),
        })
        text = json.dumps(self.gltf, indent=1) + "\n"
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)


def lambert(name, rgb):
    """Exactly Lambertian: a glTF non-metal whose specular layer is switched
    off (KHR_materials_specular specularFactor 0)."""
    return {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
    }


def pbr(name, rgb, metallic, roughness, extensions=None):
    """glTF metallic-roughness, optionally with material extensions."""
    m = {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0],
            "metallicFactor": metallic,
            "roughnessFactor": roughness,
        },
    }
    if extensions:
        m["extensions"] = extensions
    return m


def mirror(name, tint):
    """glTF metallic 1, roughness 0: vkpt's perfect mirror tinted by the base colour."""
    return {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [tint[0], tint[1], tint[2], 1.0],
            "metallicFactor": 1.0,
            "roughnessFactor": 0.0,
        },
    }


def glass_volume(name, ior):
    """Clear glass: KHR_materials_transmission with a volume (a closed
    refractive solid) and KHR_materials_ior."""
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": {"thicknessFactor": 1.0},
            "KHR_materials_ior": {"ior": ior},
        },
    }


def bubble(name, ior):
    """A dielectric with any relative IOR (below 1 too: glTF's
    KHR_materials_ior cannot say that) from the vkpt material extras."""
    return {
        "name": name,
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
        "extras": {"vkpt": {"dielectric": {"ior": ior}}},
    }


# --------------------------------------------------------------------------
# The Cornell box (Cornell University measurements, millimetres).

CORNELL_MM = {
    # name: (material, vertices of each quad, orientation)
    "floor": ("white", [[[552.8, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 559.2], [549.6, 0.0, 559.2]]], "in"),
    "ceiling": ("white", [[[556.0, 548.8, 0.0], [556.0, 548.8, 559.2], [0.0, 548.8, 559.2], [0.0, 548.8, 0.0]]], "in"),
    "back_wall": ("white", [[[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8, 559.2]]], "in"),
    "red_left_wall": ("red", [[[552.8, 0.0, 0.0], [549.6, 0.0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0.0]]], "in"),
    "green_right_wall": ("green", [[[0.0, 0.0, 559.2], [0.0, 0.0, 0.0], [0.0, 548.8, 0.0], [0.0, 548.8, 559.2]]], "in"),
    "short_box": ("white", [
        [[130.0, 165.0, 65.0], [82.0, 165.0, 225.0], [240.0, 165.0, 272.0], [290.0, 165.0, 114.0]],
        [[290.0, 0.0, 114.0], [290.0, 165.0, 114.0], [240.0, 165.0, 272.0], [240.0, 0.0, 272.0]],
        [[130.0, 0.0, 65.0], [130.0, 165.0, 65.0], [290.0, 165.0, 114.0], [290.0, 0.0, 114.0]],
        [[82.0, 0.0, 225.0], [82.0, 165.0, 225.0], [130.0, 165.0, 65.0], [130.0, 0.0, 65.0]],
        [[240.0, 0.0, 272.0], [240.0, 165.0, 272.0], [82.0, 165.0, 225.0], [82.0, 0.0, 225.0]],
    ], "out"),
    "tall_box": ("white", [
        [[423.0, 330.0, 247.0], [265.0, 330.0, 296.0], [314.0, 330.0, 456.0], [472.0, 330.0, 406.0]],
        [[423.0, 0.0, 247.0], [423.0, 330.0, 247.0], [472.0, 330.0, 406.0], [472.0, 0.0, 406.0]],
        [[472.0, 0.0, 406.0], [472.0, 330.0, 406.0], [314.0, 330.0, 456.0], [314.0, 0.0, 456.0]],
        [[314.0, 0.0, 456.0], [314.0, 330.0, 456.0], [265.0, 330.0, 296.0], [265.0, 0.0, 296.0]],
        [[265.0, 0.0, 296.0], [265.0, 330.0, 296.0], [423.0, 330.0, 247.0], [423.0, 0.0, 247.0]],
    ], "out"),
    # 130 x 105 mm, 0.1 mm below the ceiling.
    "light": ("light", [[[343.0, 548.7, 227.0], [343.0, 548.7, 332.0], [213.0, 548.7, 332.0], [213.0, 548.7, 227.0]]], "down"),
}
ROOM_CENTRE_MM = [278.0, 274.4, 279.6]


def oriented_triangles(quads, orientation):
    """Two triangles per quad, wound counter-clockwise seen from the side the
    front face must face: into the room, out of a box, or down."""
    body = centroid([p for q in quads for p in q])
    tris = []
    for q in quads:
        c = centroid(q)
        if orientation == "in":
            want = sub(ROOM_CENTRE_MM, c)
        elif orientation == "out":
            want = sub(c, body)
        else:
            want = [0.0, -1.0, 0.0]
        n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
        if dot(n, want) < 0.0:
            q = [q[0], q[3], q[2], q[1]]
        tris.append([q[0], q[1], q[2]])
        tris.append([q[0], q[2], q[3]])
    return tris


def cornell_box(path, showcase=False):
    b = Builder()
    mats = {
        "white": b.material(lambert("white", [0.725, 0.71, 0.68])),
        "red": b.material(lambert("red", [0.63, 0.065, 0.05])),
        "green": b.material(lambert("green", [0.14, 0.45, 0.091])),
    }
    light = lambert("light", [0.78, 0.78, 0.78])
    emission = [17.0, 12.0, 4.0]
    strength = max(emission)
    light["emissiveFactor"] = [e / strength for e in emission]
    light["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": strength}
    light["doubleSided"] = False
    mats["light"] = b.material(light)

    if showcase:
        mats["mirror"] = b.material(mirror("mirror", [0.9, 0.9, 0.9]))
    nodes = []
    for name, (material, quads, orientation) in CORNELL_MM.items():
        if showcase and name == "tall_box":
            material = "mirror"
        positions, normals = [], []
        for tri in oriented_triangles(quads, orientation):
            tri_m = [[round(c * 0.001, 7) for c in p] for p in tri]
            n = normalize(cross(sub(tri_m[1], tri_m[0]), sub(tri_m[2], tri_m[0])))
            positions.extend(tri_m)
            normals.extend([n, n, n])
        mesh = b.mesh(name, positions, normals, mats[material])
        nodes.append(b.node({"name": name, "mesh": mesh}))

    if showcase:
        # A glass sphere on the floor in front of the mirror box, a Phong
        # sphere on the short box (millimetres, then metres).
        glass = b.material(glass_volume("glass", 1.5))
        shiny = b.material({
            "name": "phong blue",
            "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.15, 0.5, 1.0]},
            "extras": {"vkpt": {"phong": {"kd": [0.1, 0.15, 0.5], "ks": [0.5, 0.5, 0.5], "n": 60}}},
        })
        volume = {"thicknessFactor": 1.0}
        transmission = {"transmissionFactor": 1.0}
        spheres = [
            ("glass_sphere", glass, [375.0, 90.0, 140.0], 90.0),
            ("phong_sphere", shiny, [185.0, 245.0, 168.0], 80.0),
            # An air bubble (relative IOR 1/1.5) inside the glass sphere.
            ("bubble", b.material(bubble("air in glass", 1.0 / 1.5)), [375.0, 90.0, 140.0], 40.0),
            ("rough_gold", b.material(pbr("rough gold", [1.0, 0.78, 0.34], 1.0, 0.45)),
             [150.0, 40.0, 25.0], 40.0),
            ("rough_plastic", b.material(pbr("rough red plastic", [0.6, 0.08, 0.05], 0.0, 0.35)),
             [245.0, 40.0, 25.0], 40.0),
            ("smooth_plastic", b.material(pbr("smooth blue plastic", [0.1, 0.2, 0.6], 0.0, 0.0)),
             [495.0, 50.0, 60.0], 50.0),
            ("rough_glass", b.material(pbr("rough glass", [1.0, 1.0, 1.0], 0.0, 0.3, {
                "KHR_materials_transmission": transmission,
                "KHR_materials_volume": volume,
                "KHR_materials_ior": {"ior": 1.5},
            })), [60.0, 50.0, 60.0], 50.0),
            ("green_glass", b.material(pbr("absorbing green glass", [1.0, 1.0, 1.0], 0.0, 0.0, {
                "KHR_materials_transmission": transmission,
                "KHR_materials_volume": {
                    "thicknessFactor": 1.0,
                    "attenuationColor": [0.2, 0.8, 0.3],
                    "attenuationDistance": 0.05,
                },
            })), [368.0, 390.0, 350.0], 60.0),
            ("frosted_thin", b.material(pbr("frosted thin-walled", [0.9, 0.9, 1.0], 0.0, 0.2, {
                "KHR_materials_transmission": transmission,
            })), [470.0, 420.0, 120.0], 50.0),
            ("specular_tint", b.material(pbr("half-metal, tinted specular", [0.2, 0.5, 0.3], 0.5, 0.25, {
                "KHR_materials_specular": {"specularFactor": 0.8, "specularColorFactor": [1.0, 0.5, 0.5]},
            })), [510.0, 40.0, 500.0], 40.0),
        ]
        for name, material, centre, radius in spheres:
            mesh = sphere_mesh(b, name, material, 3, [c * 0.001 for c in centre], radius * 0.001)
            nodes.append(b.node({"name": name, "mesh": mesh}))

    b.gltf["cameras"] = [{
        "name": "main",
        "type": "perspective",
        "perspective": {
            "yfov": math.radians(39.3077),
            "aspectRatio": 1.0,
            "znear": 0.01,
            "zfar": 100.0,
        },
    }]
    # glTF cameras look down their local -Z: turn 180 degrees about +Y to
    # look toward +Z, into the open side of the box.
    nodes.append(b.node({
        "name": "camera",
        "camera": 0,
        "translation": [0.278, 0.273, -0.8],
        "rotation": [0.0, 1.0, 0.0, 0.0],
    }))
    b.gltf["scenes"].append({"name": "materials-showcase" if showcase else "cornell-box", "nodes": nodes})
    b.finish(path)


# --------------------------------------------------------------------------
# The white furnace: a unit icosphere in a uniform environment.

def icosphere(subdivisions):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [normalize(v) for v in [
        [-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
        [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
        [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1],
    ]]
    faces = [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ]
    for _ in range(subdivisions):
        cache = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                verts.append(normalize(scale(add(verts[a], verts[b]), 0.5)))
                cache[key] = len(verts) - 1
            return cache[key]

        new_faces = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            new_faces += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = new_faces
    # Outward counter-clockwise winding.
    oriented = []
    for a, b, c in faces:
        n = cross(sub(verts[b], verts[a]), sub(verts[c], verts[a]))
        oriented.append([a, b, c] if dot(n, centroid([verts[a], verts[b], verts[c]])) > 0 else [a, c, b])
    return verts, oriented


def sphere_mesh(b, name, material, subdivisions, centre, radius):
    verts, faces = icosphere(subdivisions)
    normals = [normalize(v) for v in verts]
    verts = [[round(centre[i] + radius * v[i], 7) for i in range(3)] for v in verts]
    return b.mesh(name, verts, normals, material, [i for f in faces for i in f])


def white_furnace(path, material=None, subdivisions=3):
    b = Builder()
    albedo = b.material(material or lambert("albedo 0.8", [0.8, 0.8, 0.8]))
    verts, faces = icosphere(subdivisions)
    verts = [[round(c, 7) for c in v] for v in verts]
    normals = [normalize(v) for v in verts]
    mesh = b.mesh("icosphere", verts, normals, albedo, [i for f in faces for i in f])
    sphere = b.node({"name": "sphere", "mesh": mesh})
    # The sphere (radius 1, distance 4) spans 60% of the frame height.
    distance = 4.0
    half_height = math.tan(math.asin(1.0 / distance)) / 0.6
    b.gltf["cameras"] = [{
        "name": "main",
        "type": "perspective",
        "perspective": {"yfov": 2.0 * math.atan(half_height), "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0},
    }]
    cam = b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.0, distance]})
    b.gltf["scenes"].append({
        "name": "white-furnace",
        "nodes": [sphere, cam],
        "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}},
    })
    b.finish(path)


# --------------------------------------------------------------------------
# Every material path on one small frame, for GPU vs CPU comparisons.

def showcase_materials(b):
    """(material index, extra sphere inside it or None) for each material
    path, in grid order."""
    volume = {"thicknessFactor": 1.0}
    transmission = {"transmissionFactor": 1.0}
    glass = {"KHR_materials_transmission": transmission, "KHR_materials_volume": volume,
             "KHR_materials_ior": {"ior": 1.5}}
    m = b.material
    return [
        (m(lambert("diffuse", [0.8, 0.6, 0.3])), None),
        (m({"name": "phong", "extras": {"vkpt": {"phong": {"kd": [0.1, 0.15, 0.5], "ks": [0.5, 0.5, 0.5], "n": 40}}}}), None),
        (m(mirror("tinted mirror", [0.9, 0.7, 0.5])), None),
        (m(pbr("rough gold", [1.0, 0.78, 0.34], 1.0, 0.45)), None),
        (m(pbr("rough red plastic", [0.6, 0.08, 0.05], 0.0, 0.35)), None),
        (m(pbr("smooth blue plastic", [0.1, 0.2, 0.6], 0.0, 0.0)), None),
        (m(glass_volume("glass", 1.5)), m(bubble("air in glass", 1.0 / 1.5))),
        (m(pbr("rough glass", [1.0, 1.0, 1.0], 0.0, 0.3, glass)), None),
        (m(pbr("absorbing green glass", [1.0, 1.0, 1.0], 0.0, 0.0, {
            "KHR_materials_transmission": transmission,
            "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationColor": [0.2, 0.8, 0.3],
                                     "attenuationDistance": 0.3},
        })), None),
        (m(pbr("frosted thin-walled", [0.9, 0.9, 1.0], 0.0, 0.2, {"KHR_materials_transmission": transmission})), None),
        (m(pbr("half-metal, tinted specular", [0.2, 0.5, 0.3], 0.5, 0.25, {
            "KHR_materials_specular": {"specularFactor": 0.8, "specularColorFactor": [1.0, 0.5, 0.5]},
        })), None),
        (m(pbr("white rough metal", [1.0, 1.0, 1.0], 1.0, 1.0)), None),
    ]


def quad(b, name, material, corners):
    """Two triangles, front face counter-clockwise as given."""
    n = normalize(cross(sub(corners[1], corners[0]), sub(corners[2], corners[0])))
    tris = [corners[0], corners[1], corners[2], corners[0], corners[2], corners[3]]
    return b.node({"name": name, "mesh": b.mesh(name, tris, [n] * 6, material)})


def materials_grid(path):
    b = Builder()
    nodes = []
    # A striped back wall (so refraction shows), an area light above the
    # front and a dim uniform environment.
    colours = [[0.8, 0.2, 0.2], [0.8, 0.8, 0.8], [0.2, 0.3, 0.8]]
    stripes = [b.material(lambert("stripe %d" % i, c)) for i, c in enumerate(colours)]
    for i in range(8):
        x0, x1 = -3.0 + 0.75 * i, -3.0 + 0.75 * (i + 1)
        nodes.append(quad(b, "wall %d" % i, stripes[i % 3],
                          [[x0, -2.5, -1.0], [x1, -2.5, -1.0], [x1, 2.5, -1.0], [x0, 2.5, -1.0]]))
    light = lambert("light", [0.0, 0.0, 0.0])
    light["emissiveFactor"] = [1.0, 1.0, 1.0]
    light["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": 6.0}
    nodes.append(quad(b, "light", b.material(light),
                      [[-1.0, 2.4, 0.0], [-1.0, 2.4, 2.0], [1.0, 2.4, 2.0], [1.0, 2.4, 0.0]]))
    for k, (material, inner) in enumerate(showcase_materials(b)):
        centre = [-1.5 + (k % 4), 1.0 - (k // 4), 0.0]
        mesh = sphere_mesh(b, "sphere %d" % k, material, 2, centre, 0.42)
        nodes.append(b.node({"name": "sphere %d" % k, "mesh": mesh}))
        if inner is not None:
            mesh = sphere_mesh(b, "inner %d" % k, inner, 2, centre, 0.2)
            nodes.append(b.node({"name": "inner %d" % k, "mesh": mesh}))
    half_height = 1.65
    b.gltf["cameras"] = [{
        "name": "main",
        "type": "perspective",
        "perspective": {"yfov": 2.0 * math.atan(half_height / 6.0), "aspectRatio": 4.0 / 3.0,
                        "znear": 0.01, "zfar": 100.0},
    }]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.0, 6.0]}))
    b.gltf["scenes"].append({
        "name": "materials-grid",
        "nodes": nodes,
        "extras": {"vkpt": {"environment": [0.3, 0.3, 0.3]}},
    })
    b.finish(path)


# --------------------------------------------------------------------------
# Read back and check what the spec requires.

def validate(path):
    with open(path, encoding="utf-8") as f:
        g = json.load(f)
    assert g["asset"]["version"] == "2.0"
    buffers = []
    for buf in g["buffers"]:
        prefix = "data:application/octet-stream;base64,"
        assert buf["uri"].startswith(prefix), path
        data = base64.b64decode(buf["uri"][len(prefix):])
        assert len(data) == buf["byteLength"], (path, len(data), buf["byteLength"])
        buffers.append(data)
    for view in g["bufferViews"]:
        assert view["byteOffset"] + view["byteLength"] <= len(buffers[view["buffer"]]), path
    sizes = {"SCALAR": 1, "VEC3": 3}
    csize = {5123: 2, 5126: 4}
    for acc in g["accessors"]:
        view = g["bufferViews"][acc["bufferView"]]
        assert acc["count"] * sizes[acc["type"]] * csize[acc["componentType"]] <= view["byteLength"], path
    for mesh in g["meshes"]:
        for prim in mesh["primitives"]:
            pos = g["accessors"][prim["attributes"]["POSITION"]]
            assert "min" in pos and "max" in pos, (path, mesh["name"])
            if "indices" in prim:
                idx = g["accessors"][prim["indices"]]
                view = g["bufferViews"][idx["bufferView"]]
                data = buffers[view["buffer"]][view["byteOffset"]:view["byteOffset"] + view["byteLength"]]
                values = struct.unpack("<%dH" % idx["count"], data[: 2 * idx["count"]])
                assert max(values) < pos["count"], path


def main():
    outputs = [
        (os.path.join(HERE, "cornell-box.gltf"), cornell_box),
        (os.path.join(HERE, "white-furnace.gltf"), white_furnace),
        (os.path.join(HERE, "furnace-glass-1.5.gltf"),
         lambda p: white_furnace(p, glass_volume("glass ior 1.5", 1.5))),
        (os.path.join(HERE, "furnace-glass-0.67.gltf"), lambda p: white_furnace(p, bubble("bubble ior 0.67", 0.67))),
        (os.path.join(HERE, "furnace-mirror-0.8.gltf"), lambda p: white_furnace(p, mirror("mirror 0.8", [0.8, 0.8, 0.8]))),
        (os.path.join(HERE, "materials-showcase.gltf"), lambda p: cornell_box(p, showcase=True)),
        (os.path.join(HERE, "materials-grid.gltf"), materials_grid),
        (os.path.join(HERE, "furnace-rough-metal.gltf"),
         lambda p: white_furnace(p, pbr("white rough metal", [1.0, 1.0, 1.0], 1.0, 1.0), subdivisions=5)),
    ]
    for path, build in outputs:
        build(path)
        validate(path)
        print("wrote and checked", os.path.relpath(path))


if __name__ == "__main__":
    main()
