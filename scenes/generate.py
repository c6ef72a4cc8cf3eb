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

materials-showcase.gltf: the Cornell box with a mirror tall box, a glass
sphere (IOR 1.5) on the floor and a normalized-Phong sphere (vkpt material
extras) on the short box.

textured.gltf: every texture feature vkpt renders, with small PNGs made
here: a floor with an sRGB checker (REPEAT, KHR_texture_transform scale and
rotation, bilinear), a back wall reading TEXCOORD_1 with MIRRORED_REPEAT
along S and CLAMP_TO_EDGE along T (NEAREST), a normal-mapped panel without
TANGENT (vkpt generates tangents), a striped emissive-textured light, and
an alpha-MASK cutout grid between the light and the floor whose holes cast
a checkered shadow.

alpha-mask.gltf, alpha-holes.gltf: a grey square above a white floor under
a uniform environment; in the first it is an alpha-MASK quad whose 4x4
NEAREST alpha checker cuts out every other cell, in the second the opaque
cells are real geometry. Both must render the same.
"""

import base64
import json
import math
import os
import struct
import zlib

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
        self.gltf["buffers"].append({
            "byteLength": len(self.data),
            "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.data)).decode("ascii"),
        })
        text = json.dumps(self.gltf, indent=1) + "\n"
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)


def lambert(name, rgb):
    return {
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [rgb[0], rgb[1], rgb[2], 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
    }


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
    b.gltf["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    mats = {
        "white": b.material(lambert("white", [0.725, 0.71, 0.68])),
        "red": b.material(lambert("red", [0.63, 0.065, 0.05])),
        "green": b.material(lambert("green", [0.14, 0.45, 0.091])),
    }
    light = lambert("light", [0.78, 0.78, 0.78])
    emission = [17.0, 12.0, 4.0]
    strength = max(emission)
    light["emissiveFactor"] = [e / strength for e in emission]
    light["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
    light["doubleSided"] = False
    mats["light"] = b.material(light)

    if showcase:
        b.gltf["extensionsUsed"] += ["KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior"]
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
        for name, material, centre, radius in [
            ("glass_sphere", glass, [375.0, 90.0, 140.0], 90.0),
            ("phong_sphere", shiny, [185.0, 245.0, 168.0], 80.0),
        ]:
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


def white_furnace(path, material=None, extensions=()):
    b = Builder()
    if extensions:
        b.gltf["extensionsUsed"] = list(extensions)
    albedo = b.material(material or lambert("albedo 0.8", [0.8, 0.8, 0.8]))
    verts, faces = icosphere(3)
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
# Textured scenes: PNG images written here (zlib, no external libraries).

def png_bytes(rows):
    """An 8-bit RGBA PNG from rows of (r, g, b, a) tuples, top row first."""
    height, width = len(rows), len(rows[0])
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def checker_rows(n, cell, a, b):
    return [[a if ((x // cell) + (y // cell)) % 2 == 0 else b for x in range(n)] for y in range(n)]


def letter_rows():
    """16x16: a red 'F' on light grey with a blue top row and a green left
    column, so orientation and mirroring are visible."""
    rows = [[(220, 220, 220, 255)] * 16 for _ in range(16)]
    for y in range(3, 13):
        rows[y][5] = (200, 30, 30, 255)
    for x in range(5, 12):
        rows[3][x] = (200, 30, 30, 255)
    for x in range(5, 10):
        rows[7][x] = (200, 30, 30, 255)
    for x in range(16):
        rows[0][x] = (30, 60, 200, 255)
    for y in range(16):
        rows[y][0] = (30, 160, 60, 255)
    return rows


def bump_normal_rows(n, bumps):
    """Tangent-space normals (+X right, +Y up the image) of a grid of
    spherical-cap bumps, encoded as RGB = (N + 1) / 2."""
    rows = []
    size = n / bumps
    for y in range(n):
        row = []
        for x in range(n):
            cx = (x + 0.5) % size / size * 2.0 - 1.0
            cy = (y + 0.5) % size / size * 2.0 - 1.0
            r2 = cx * cx + cy * cy
            if r2 < 0.8:
                # Up the image is -y in rows: the normal tilts outward.
                nx, ny = cx * 0.7, -cy * 0.7
            else:
                nx, ny = 0.0, 0.0
            nz = math.sqrt(max(0.0, 1.0 - nx * nx - ny * ny))
            row.append(tuple(int(round((c * 0.5 + 0.5) * 255)) for c in (nx, ny, nz)) + (255,))
        rows.append(row)
    return rows


def stripe_rows(n):
    return [[(255, 240, 200, 255) if (x // 2) % 2 == 0 else (60, 60, 60, 255) for x in range(n)] for _ in range(n)]


class TexturedBuilder(Builder):
    def __init__(self):
        super().__init__()
        self.gltf.update({"images": [], "samplers": [], "textures": []})

    def accessor(self, values, type_, fmt):
        blob = b"".join(struct.pack("<" + fmt, *v) for v in values)
        self.gltf["accessors"].append({
            "bufferView": self._view(blob, 34962),
            "componentType": 5126,
            "count": len(values),
            "type": type_,
        })
        return len(self.gltf["accessors"]) - 1

    def texture(self, rows, sampler, name, embed_in_buffer):
        """An image as a bufferView (as a .glb embeds it) or a data URI."""
        png = png_bytes(rows)
        if embed_in_buffer:
            image = {"name": name, "mimeType": "image/png", "bufferView": self._view(png, None)}
            del self.gltf["bufferViews"][image["bufferView"]]["target"]
        else:
            image = {"name": name, "uri": "data:image/png;base64," + base64.b64encode(png).decode("ascii")}
        self.gltf["images"].append(image)
        self.gltf["samplers"].append(sampler)
        self.gltf["textures"].append({"source": len(self.gltf["images"]) - 1,
                                      "sampler": len(self.gltf["samplers"]) - 1})
        return len(self.gltf["textures"]) - 1

    def quad(self, name, corners, material, uv0=None, uv1=None):
        """A quad p0 p1 p2 p3 (counter-clockwise seen from the front), two
        triangles, with optional per-corner texture coordinates."""
        n = normalize(cross(sub(corners[1], corners[0]), sub(corners[2], corners[0])))
        prim = {
            "attributes": {
                "POSITION": self.vec3_accessor(corners, True),
                "NORMAL": self.vec3_accessor([n] * 4, False),
            },
            "indices": self.index_accessor([0, 1, 2, 0, 2, 3]),
            "material": material,
            "mode": 4,
        }
        if uv0:
            prim["attributes"]["TEXCOORD_0"] = self.accessor(uv0, "VEC2", "2f")
        if uv1:
            prim["attributes"]["TEXCOORD_1"] = self.accessor(uv1, "VEC2", "2f")
        self.gltf["meshes"].append({"name": name, "primitives": [prim]})
        return self.node({"name": name, "mesh": len(self.gltf["meshes"]) - 1})


REPEAT, CLAMP, MIRROR = 10497, 33071, 33648
LINEAR, NEAREST = 9729, 9728
UNIT_UV = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]


def horizontal(y, x0, x1, z0, z1):
    """Corners of a quad at height y facing +Y; with UNIT_UV, u runs along
    +x and v along +z."""
    return [[x0, y, z1], [x1, y, z1], [x1, y, z0], [x0, y, z0]]


def look_down_camera(b, position, pitch):
    b.gltf["cameras"] = [{"name": "main", "type": "perspective",
                          "perspective": {"yfov": 0.8, "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0}}]
    return b.node({"name": "camera", "camera": 0, "translation": position,
                   "rotation": [math.sin(-pitch / 2), 0.0, 0.0, math.cos(pitch / 2)]})


def textured_scene(path):
    b = TexturedBuilder()
    b.gltf["extensionsUsed"] = ["KHR_texture_transform"]
    checker = b.texture(checker_rows(8, 1, (230, 200, 120, 255), (40, 70, 120, 255)),
                        {"magFilter": LINEAR, "wrapS": REPEAT, "wrapT": REPEAT}, "checker", True)
    letter = b.texture(letter_rows(), {"magFilter": NEAREST, "wrapS": MIRROR, "wrapT": CLAMP}, "letter F", False)
    bumps = b.texture(bump_normal_rows(32, 4), {}, "bumps", True)
    stripes = b.texture(stripe_rows(16), {"magFilter": NEAREST}, "stripes", False)
    holes = b.texture(checker_rows(4, 1, (255, 120, 40, 255), (255, 120, 40, 0)),
                      {"magFilter": NEAREST, "wrapS": CLAMP, "wrapT": CLAMP}, "holes", True)
    floor = b.material({
        "name": "checker floor",
        "pbrMetallicRoughness": {
            "baseColorTexture": {"index": checker, "extensions": {
                "KHR_texture_transform": {"scale": [3.0, 3.0], "rotation": 0.3, "offset": [0.1, 0.0]}}},
            "metallicFactor": 0.0, "roughnessFactor": 1.0},
    })
    wall = b.material({
        "name": "letter wall",
        "pbrMetallicRoughness": {"baseColorTexture": {"index": letter, "texCoord": 1},
                                 "metallicFactor": 0.0, "roughnessFactor": 1.0},
    })
    panel = b.material({
        "name": "bumpy panel",
        "normalTexture": {"index": bumps, "scale": 1.0},
        "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
    })
    light = b.material({
        "name": "striped light",
        "emissiveFactor": [1.0, 1.0, 1.0],
        "emissiveTexture": {"index": stripes},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 15.0}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
    })
    b.gltf["extensionsUsed"].append("KHR_materials_emissive_strength")
    cutout = b.material({
        "name": "cutout grid",
        "alphaMode": "MASK",
        "alphaCutoff": 0.5,
        "doubleSided": True,
        "pbrMetallicRoughness": {"baseColorTexture": {"index": holes}, "metallicFactor": 0.0, "roughnessFactor": 1.0},
    })
    nodes = [
        b.quad("floor", horizontal(0.0, -2.0, 2.0, -2.0, 2.0), floor, UNIT_UV),
        # Back wall facing +Z; TEXCOORD_1 runs past [0, 1] to show the wrap modes.
        b.quad("wall", [[-2.0, 0.0, -2.0], [2.0, 0.0, -2.0], [2.0, 2.5, -2.0], [-2.0, 2.5, -2.0]], wall,
               UNIT_UV, [[-1.0, 1.25], [2.0, 1.25], [2.0, -0.25], [-1.0, -0.25]]),
        # Left panel facing +X, normal-mapped, no TANGENT.
        b.quad("panel", [[-1.9, 0.0, 0.5], [-1.9, 0.0, -1.5], [-1.9, 2.0, -1.5], [-1.9, 2.0, 0.5]], panel, UNIT_UV),
        # Light facing down.
        b.quad("light", [[-0.6, 2.4, -0.6], [0.6, 2.4, -0.6], [0.6, 2.4, 0.6], [-0.6, 2.4, 0.6]], light, UNIT_UV),
        b.quad("cutout", horizontal(0.9, -0.6, 0.6, -0.6, 0.6), cutout, UNIT_UV),
    ]
    nodes.append(look_down_camera(b, [0.0, 2.8, 4.4], math.atan2(2.2, 4.4)))
    b.gltf["scenes"].append({"name": "textured", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [0.05, 0.05, 0.05]}}})
    b.finish(path)


def alpha_scene(path, real_holes):
    b = TexturedBuilder()
    white = b.material(lambert("white floor", [0.8, 0.8, 0.8]))
    nodes = [b.quad("floor", horizontal(0.0, -1.5, 1.5, -1.5, 1.5), white)]
    grey = {"name": "grey", "doubleSided": True,
            "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}
    if real_holes:
        m = b.material(grey)
        # Texel (i, j) covers u in [i/4, (i+1)/4], v in [j/4, (j+1)/4]:
        # x = u - 0.5, z = v - 0.5. Opaque where i + j is even.
        for j in range(4):
            for i in range(4):
                if (i + j) % 2 == 0:
                    x0, z0 = i / 4 - 0.5, j / 4 - 0.5
                    nodes.append(b.quad("cell %d %d" % (i, j), horizontal(0.5, x0, x0 + 0.25, z0, z0 + 0.25), m))
    else:
        holes = b.texture(checker_rows(4, 1, (255, 255, 255, 255), (255, 255, 255, 0)),
                          {"magFilter": NEAREST, "wrapS": CLAMP, "wrapT": CLAMP}, "holes", True)
        grey["alphaMode"] = "MASK"
        grey["pbrMetallicRoughness"]["baseColorTexture"] = {"index": holes}
        nodes.append(b.quad("cutout", horizontal(0.5, -0.5, 0.5, -0.5, 0.5), b.material(grey), UNIT_UV))
    nodes.append(look_down_camera(b, [0.0, 2.2, 2.2], math.pi / 4))
    b.gltf["scenes"].append({"name": "alpha", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}}})
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
    sizes = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
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
    transmission = ["KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior"]
    outputs = [
        (os.path.join(HERE, "cornell-box.gltf"), cornell_box),
        (os.path.join(HERE, "white-furnace.gltf"), white_furnace),
        (os.path.join(HERE, "furnace-glass-1.5.gltf"),
         lambda p: white_furnace(p, glass_volume("glass ior 1.5", 1.5), transmission)),
        (os.path.join(HERE, "furnace-glass-0.67.gltf"), lambda p: white_furnace(p, bubble("bubble ior 0.67", 0.67))),
        (os.path.join(HERE, "furnace-mirror-0.8.gltf"), lambda p: white_furnace(p, mirror("mirror 0.8", [0.8, 0.8, 0.8]))),
        (os.path.join(HERE, "materials-showcase.gltf"), lambda p: cornell_box(p, showcase=True)),
        (os.path.join(HERE, "textured.gltf"), textured_scene),
        (os.path.join(HERE, "alpha-mask.gltf"), lambda p: alpha_scene(p, False)),
        (os.path.join(HERE, "alpha-holes.gltf"), lambda p: alpha_scene(p, True)),
    ]
    for path, build in outputs:
        build(path)
        validate(path)
        print("wrote and checked", os.path.relpath(path))


if __name__ == "__main__":
    main()
