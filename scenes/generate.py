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

cornell-spheres.gltf: the same room and light without the boxes, holding a
solid glass sphere (KHR_materials_transmission + volume, IOR 1.5) and a white
perfect mirror sphere (metallic 1, roughness 0), flat-shaded UV spheres of
2208 triangles each (CORNELL_SPHERES_MM): benches/mitsuba_cornell.py renders
the same triangles in Mitsuba 3.

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
the sphere shows the directional albedo E(cos theta_o) that tests/suite/furnace.rs
computes by quadrature.

furnace-clearcoat.gltf: the white furnace with a white Lambertian base
(specularFactor 0) under a clear coat (KHR_materials_clearcoat, factor 1,
roughness 0.5): each pixel shows (1 - blend) + blend E_ggx(cos theta_o),
blend the coat's Fresnel (Schlick, F0 0.04), which tests/suite/furnace.rs
computes by quadrature.

coat-grid.gltf: KHR_materials_clearcoat and KHR_materials_anisotropy, one
sphere each in a 4 x 2 grid (rough and smooth coats over plastic and
metal, a coat over an anisotropic base, anisotropic metals with and
without rotation, anisotropic rough glass, an anisotropic metal of
roughness 0), the spheres carrying TANGENTs around their vertical axis,
before a striped wall under an area light: the GPU vs CPU comparison's
scene for those lobes.

lights-showcase.gltf: a grey floor with a white icosphere and a mirror
icosphere, lit by one light of every analytic kind (KHR_lights_punctual):
a point light with a range, a spot light, a spherical light (a point light
with vkpt extras radius), a sun disk (a directional light with vkpt extras
angular_diameter), a plain directional light, one emissive quad, and a dim
uniform environment.

env-sky.gltf: the same floor and spheres lit only by the bundled
environment map env/sky-with-sun.exr (written by
`cargo run --release --example sky_with_sun`), a sky with a small bright sun.

depth-of-field.gltf: an orange sphere on a grey floor, in focus 2.5 m from an
85 mm f/1.2 lens with six straight blades (vkpt camera extras), lit by a
dim overhead area light, a spherical light beside the subject (a point
light with vkpt extras radius) and the bundled sky map dimmed to 0.25;
small bright emissive squares 4 to 12 m behind and 1.3 m in front of the
subject blur into hexagons (polygonal bokeh). A second camera, "ortho",
views the subject orthographically from 30 degrees above.

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

animated/moving-square.gltf: a white emissive square crossing a black
background at constant speed (x from -1 to +1 over 0..1 s, LINEAR), for
--time, --frames and motion blur (--shutter): the blurred edge of a square
moving at constant speed is a linear ramp.

animated/interpolation-test.gltf: three cubes rising and falling with STEP,
LINEAR and CUBICSPLINE translation and one turning (LINEAR rotation), in
the spirit of Khronos' InterpolationTest (whose binary buffer could not be
fetched here).
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
            # (Finite ones only: scenes/hard/degenerate.gltf stores NaN and
            # infinity on purpose, and JSON cannot hold them.)
            stored = [struct.unpack("<3f", struct.pack("<3f", *v)) for v in values]
            stored = [v for v in stored if all(math.isfinite(c) for c in v)]
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

# cornell-spheres.gltf: the room and light above without the two boxes, and
# two spheres resting 1 mm above the floor (name: (material, centre, radius),
# millimetres): a white perfect mirror at the back on the red side, solid
# glass of IOR 1.5 in front on the green side. benches/mitsuba_cornell.py
# builds its Mitsuba scene from the same triangles.
CORNELL_SPHERES_MM = {
    "mirror_sphere": ("mirror", [395.0, 101.0, 370.0], 100.0),
    "glass_sphere": ("glass", [170.0, 101.0, 190.0], 100.0),
}
CORNELL_SPHERES_WITHOUT = ("short_box", "tall_box")


def uv_sphere_triangles(centre_mm, radius_mm, rings=24, segments=48):
    """A UV sphere (`rings` bands of latitude, `segments` of longitude) as
    triangles in metres, rounded as the walls are, wound counter-clockwise
    seen from outside. Meant to be shaded flat (face normals): smooth
    normals would leave room for renderers to differ in how they bend them."""
    def point(i, j):
        theta = math.pi * i / rings
        phi = 2.0 * math.pi * j / segments
        d = [math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)]
        return [round((centre_mm[k] + radius_mm * d[k]) * 0.001, 7) for k in range(3)]

    centre = [c * 0.001 for c in centre_mm]
    tris = []
    for i in range(rings):
        for j in range(segments):
            a, b_ = point(i, j), point(i, j + 1)
            c, d = point(i + 1, j), point(i + 1, j + 1)
            quad_tris = []
            if i > 0:  # at the poles the band's quad is one triangle
                quad_tris.append([a, b_, d])
            if i < rings - 1:
                quad_tris.append([a, d, c])
            for t in quad_tris:
                n = cross(sub(t[1], t[0]), sub(t[2], t[0]))
                if dot(n, sub(centroid(t), centre)) < 0.0:
                    t = [t[0], t[2], t[1]]
                tris.append(t)
    return tris


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


def cornell_box(path, showcase=False, glass_and_mirror=False, sphere_rings=24):
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
    if glass_and_mirror:
        mats["mirror"] = b.material(mirror("white mirror", [1.0, 1.0, 1.0]))
        mats["glass"] = b.material(glass_volume("glass", 1.5))
    nodes = []
    for name, (material, quads, orientation) in CORNELL_MM.items():
        if glass_and_mirror and name in CORNELL_SPHERES_WITHOUT:
            continue
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

    if glass_and_mirror:
        for name, (material, centre, radius) in CORNELL_SPHERES_MM.items():
            positions, normals = [], []
            for tri in uv_sphere_triangles(centre, radius, sphere_rings, 2 * sphere_rings):
                n = normalize(cross(sub(tri[1], tri[0]), sub(tri[2], tri[0])))
                positions.extend(tri)
                normals.extend([n, n, n])
            mesh = b.mesh(name, positions, normals, mats[material])
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
    name = "materials-showcase" if showcase else "cornell-spheres" if glass_and_mirror else "cornell-box"
    b.gltf["scenes"].append({"name": name, "nodes": nodes})
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
# Hard cases (scenes/hard/): numerical stability, rendered in tests/suite/hard_cases.rs.

HARD = os.path.join(HERE, "hard")


def transformed_cornell(path, translation=None, scale_factor=None, camera_distance=None):
    """The bundled Cornell box with every node (camera included) under one
    parent node that translates or scales it: the same image is expected
    (radiance does not depend on scale). camera_distance moves the camera
    back along its axis to that distance from the box's open front (z = 0)
    and narrows its field of view so the back wall fills the frame as
    before."""
    with open(os.path.join(HERE, "cornell-box.gltf"), encoding="utf-8") as f:
        g = json.load(f)
    if camera_distance is not None:
        cam_node = next(n for n in g["nodes"] if "camera" in n)
        back_wall = 0.559
        old = back_wall - cam_node["translation"][2]
        cam = g["cameras"][cam_node["camera"]]["perspective"]
        half = math.tan(0.5 * cam["yfov"]) * old
        cam["yfov"] = 2.0 * math.atan(half / (back_wall + camera_distance))
        cam["zfar"] = 1000.0
        cam_node["translation"][2] = -camera_distance
    root = {"name": "transform", "children": list(g["scenes"][0]["nodes"])}
    if translation is not None:
        root["translation"] = translation
    if scale_factor is not None:
        root["scale"] = [scale_factor] * 3
    g["nodes"].append(root)
    g["scenes"][0]["nodes"] = [len(g["nodes"]) - 1]
    g["scenes"][0]["name"] = os.path.splitext(os.path.basename(path))[0]
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(json.dumps(g, indent=1) + "\n")


def perspective(name, yfov_degrees, aspect=1.0):
    return {
        "name": name,
        "type": "perspective",
        "perspective": {"yfov": math.radians(yfov_degrees), "aspectRatio": aspect, "znear": 0.001, "zfar": 1000.0},
    }


def inside_sphere(path, translation=None, scale_factor=None, hole=False):
    """A camera inside a closed icosphere (two meshes, split at the equator,
    so rays also meet edges shared between meshes), facing inward, lit only
    by a white environment outside: any ray that escapes makes a pixel
    non-black. hole=True removes one triangle (the planted leak)."""
    b = Builder()
    verts, faces = icosphere(3)
    verts = [[round(c, 7) for c in v] for v in verts]
    if hole:
        faces = faces[1:]
    inward = [[a, c, b_] for a, b_, c in faces]
    wall = b.material(lambert("wall 0.8", [0.8, 0.8, 0.8]))
    nodes = []
    for name, keep in [("north", lambda z: z >= 0.0), ("south", lambda z: z < 0.0)]:
        part = [f for f in inward if keep(centroid([verts[i] for i in f])[2])]
        normals = [scale(normalize(v), -1.0) for v in verts]
        mesh = b.mesh(name, verts, normals, wall, [i for f in part for i in f])
        nodes.append(b.node({"name": name, "mesh": mesh}))
    b.gltf["cameras"] = [perspective("inside", 90.0)]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": [0.1, -0.2, 0.3]}))
    root = {"name": "transform", "children": nodes}
    if translation is not None:
        root["translation"] = translation
    if scale_factor is not None:
        root["scale"] = [scale_factor] * 3
    b.gltf["scenes"].append({
        "name": "inside-sphere",
        "nodes": [b.node(root)],
        "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}},
    })
    b.finish(path)


def grazing_plane(path):
    """A 1000 x 1000 plane of 64 x 64 quads (shared edges everywhere),
    tilted by a fraction of a degree so it is not axis-aligned, albedo 0.5,
    under a white environment; the camera skims it 1 cm above. Lit by the
    whole sky and nothing else, every point of the plane has radiance
    exactly 0.5, every sky pixel 1: a black rim (self-intersection) or a
    leak through an edge (radiance 1 on the plane) is visible."""
    b = Builder()
    n, half = 64, 500.0
    positions, normals, indices = [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            positions.append([-half + 2 * half * i / n, 0.0, -half + 2 * half * j / n])
            normals.append([0.0, 1.0, 0.0])
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            # Counter-clockwise seen from +Y.
            indices += [a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]
    grey = b.material(lambert("grey 0.5", [0.5, 0.5, 0.5]))
    mesh = b.mesh("plane", positions, normals, grey, indices)
    tilt = [math.sin(math.radians(0.15)), 0.0, math.sin(math.radians(0.1))]
    w = math.sqrt(1.0 - dot(tilt, tilt))
    plane = b.node({"name": "plane", "mesh": mesh, "rotation": [tilt[0], 0.0, tilt[2], w]})
    b.gltf["cameras"] = [perspective("skimming", 8.0, 2.0)]
    # Looking along -Z, pitched down 2 degrees, 1 cm above the plane's centre.
    pitch = math.radians(-2.0) / 2.0
    cam = b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.01, 0.0],
                  "rotation": [math.sin(pitch), 0.0, 0.0, math.cos(pitch)]})
    b.gltf["scenes"].append({
        "name": "grazing-plane",
        "nodes": [plane, cam],
        "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}},
    })
    b.finish(path)


def box_quads(lo, hi):
    """The six faces of an axis-aligned box, each wound outward."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [
        [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],  # +z
        [[x1, y0, z0], [x0, y0, z0], [x0, y1, z0], [x1, y1, z0]],  # -z
        [[x1, y0, z1], [x1, y0, z0], [x1, y1, z0], [x1, y1, z1]],  # +x
        [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],  # -x
        [[x0, y1, z1], [x1, y1, z1], [x1, y1, z0], [x0, y1, z0]],  # +y
        [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],  # -y
    ]


def add_box(b, name, material, lo, hi):
    positions, normals = [], []
    for q in box_quads(lo, hi):
        n = normalize(cross(sub(q[1], q[0]), sub(q[2], q[0])))
        for tri in ([q[0], q[1], q[2]], [q[0], q[2], q[3]]):
            positions.extend(tri)
            normals.extend([n, n, n])
    return b.node({"name": name, "mesh": b.mesh(name, positions, normals, material)})


def glass_and_tiny_light(path):
    """A thick glass slab (total internal reflection inside), a stack of
    eight thin glass plates (long chains of refractions) on a grey floor,
    lit by a 2 mm square light of radiance 2e6 and a dim environment."""
    b = Builder()
    b.gltf["extensionsUsed"] = ["KHR_materials_emissive_strength", "KHR_materials_transmission",
                                "KHR_materials_volume", "KHR_materials_ior"]
    grey = b.material(lambert("floor", [0.5, 0.5, 0.5]))
    glass = b.material(glass_volume("glass", 1.5))
    light = lambert("tiny light", [0.0, 0.0, 0.0])
    light["emissiveFactor"] = [1.0, 1.0, 1.0]
    light["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0e6}}
    bright = b.material(light)
    nodes = [add_box(b, "floor", grey, [-2.0, -0.1, -2.0], [2.0, 0.0, 2.0])]
    nodes.append(add_box(b, "thick slab", glass, [-0.6, 0.0, -0.2], [-0.1, 0.4, 0.2]))
    for k in range(8):
        z = -0.3 + 0.08 * k
        nodes.append(add_box(b, "plate %d" % k, glass, [0.1, 0.0, z], [0.6, 0.5, z + 0.02]))
    # The light faces down, 1.5 m up.
    s = 0.001
    q = [[-s, 1.5, -s], [-s, 1.5, s], [s, 1.5, s], [s, 1.5, -s]]
    nodes.append(b.node({"name": "tiny light", "mesh": b.mesh(
        "tiny light", [q[0], q[1], q[2], q[0], q[2], q[3]], [[0.0, -1.0, 0.0]] * 6, bright)}))
    b.gltf["cameras"] = [perspective("main", 40.0)]
    pitch = math.radians(-25.0) / 2.0
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": [0.0, 1.0, 2.0],
                         "rotation": [math.sin(pitch), 0.0, 0.0, math.cos(pitch)]}))
    b.gltf["scenes"].append({
        "name": "glass-and-tiny-light",
        "nodes": nodes,
        "extras": {"vkpt": {"environment": [0.05, 0.05, 0.05]}},
    })
    b.finish(path)


def degenerate(path):
    """Valid quads plus every kind of bad geometry the loader must drop and
    count: zero-area triangles (collinear points, a repeated vertex), a NaN
    and an infinite position, and NaN / infinite / zero vertex normals
    (replaced by the face normal). Expected counts: see tests/suite/hard_cases.rs."""
    b = Builder()
    nan, inf = float("nan"), float("inf")
    white = b.material(lambert("white", [0.8, 0.8, 0.8]))
    up = [0.0, 0.0, 1.0]
    good = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, -1, 0], [1, 1, 0], [-1, 1, 0]]
    zero_area = [[0, 0, 0], [1, 1, 0], [2, 2, 0],      # collinear
                 [0.5, 0.5, 0], [0.5, 0.5, 0], [1, 0, 0],  # repeated vertex
                 [0.3, 0.3, 0], [0.3, 0.3, 0], [0.3, 0.3, 0]]  # a point
    bad_pos = [[0, 0, 0], [nan, 0, 0], [0, 1, 0],
               [0, 0, 0], [1, 0, 0], [0, inf, 0]]
    positions = good + zero_area + bad_pos
    normals = [up] * len(positions)
    mesh_a = b.mesh("mixed", positions, normals, white)
    # A second mesh: a valid quad whose normals are NaN, infinite and zero.
    quad = [[-1, -1, -0.5], [1, -1, -0.5], [1, 1, -0.5], [-1, -1, -0.5], [1, 1, -0.5], [-1, 1, -0.5]]
    mesh_b = b.mesh("bad normals", quad, [[nan, 0, 1], [0, inf, 0], [0, 0, 0], up, up, up], white)
    b.gltf["cameras"] = [perspective("main", 60.0)]
    nodes = [b.node({"name": "mixed", "mesh": mesh_a}), b.node({"name": "bad normals", "mesh": mesh_b}),
             b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.0, 3.0]})]
    b.gltf["scenes"].append({"name": "degenerate", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}}})
    b.finish(path)


def hard_cases():
    os.makedirs(HARD, exist_ok=True)
    return [
        (os.path.join(HARD, "cornell-translated-1e5.gltf"),
         lambda p: transformed_cornell(p, translation=[1.0e5, 1.0e5, 1.0e5])),
        (os.path.join(HARD, "cornell-translated-1e6.gltf"),
         lambda p: transformed_cornell(p, translation=[1.0e6, -1.0e6, 1.0e6])),
        (os.path.join(HARD, "cornell-translated-1e7.gltf"),
         lambda p: transformed_cornell(p, translation=[1.0e7, 1.0e7, -1.0e7])),
        (os.path.join(HARD, "cornell-camera-30m.gltf"), lambda p: transformed_cornell(p, camera_distance=30.0)),
        (os.path.join(HARD, "cornell-translated-1e5-camera-30m.gltf"),
         lambda p: transformed_cornell(p, translation=[1.0e5, 1.0e5, 1.0e5], camera_distance=30.0)),
        (os.path.join(HARD, "cornell-scaled-1e-3.gltf"), lambda p: transformed_cornell(p, scale_factor=1.0e-3)),
        (os.path.join(HARD, "cornell-scaled-1e4.gltf"), lambda p: transformed_cornell(p, scale_factor=1.0e4)),
        # An icosahedron (20 faces) with smooth normals: shading normals up to
        # 37 degrees from the geometric ones, in a uniform environment.
        (os.path.join(HARD, "low-poly-smooth-sphere.gltf"), lambda p: white_furnace(p, subdivisions=0)),
        (os.path.join(HARD, "inside-sphere.gltf"), inside_sphere),
        (os.path.join(HARD, "inside-sphere-translated-1e5.gltf"),
         lambda p: inside_sphere(p, translation=[1.0e5, -1.0e5, 1.0e5])),
        (os.path.join(HARD, "inside-sphere-scaled-1e-3.gltf"), lambda p: inside_sphere(p, scale_factor=1.0e-3)),
        (os.path.join(HARD, "inside-sphere-with-hole.gltf"), lambda p: inside_sphere(p, hole=True)),
        (os.path.join(HARD, "grazing-plane.gltf"), grazing_plane),
        (os.path.join(HARD, "glass-and-tiny-light.gltf"), glass_and_tiny_light),
        (os.path.join(HARD, "degenerate.gltf"), degenerate),
    ]

# --------------------------------------------------------------------------
# Lights: every analytic light kind, and an environment map.

def quad_mesh(b, name, material, corners):
    """A quad from four counter-clockwise corners (seen from its front)."""
    n = normalize(cross(sub(corners[1], corners[0]), sub(corners[2], corners[0])))
    return b.mesh(name, corners, [n] * 4, material, [0, 1, 2, 0, 2, 3])


def look_at_rotation(eye, target):
    """Quaternion turning -Z toward target - eye, keeping +Y up."""
    f = normalize(sub(target, eye))
    r = normalize(cross(f, [0.0, 1.0, 0.0]))
    u = cross(r, f)
    # Columns of the rotation: r, u, -f.
    m = [[r[0], u[0], -f[0]], [r[1], u[1], -f[1]], [r[2], u[2], -f[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        return [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    if m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        return [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
    return [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]


def lights_floor_and_spheres(b):
    grey = b.material(lambert("floor", [0.5, 0.5, 0.5]))
    white = b.material(lambert("white", [0.8, 0.8, 0.8]))
    chrome = b.material(mirror("mirror", [0.9, 0.9, 0.9]))
    floor = quad_mesh(b, "floor", grey, [[-4, 0, 4], [4, 0, 4], [4, 0, -4], [-4, 0, -4]])
    nodes = [b.node({"name": "floor", "mesh": floor})]
    nodes.append(b.node({"name": "white sphere", "mesh": sphere_mesh(b, "white sphere", white, 2, [-0.7, 0.6, 0.0], 0.6)}))
    nodes.append(b.node({"name": "mirror sphere", "mesh": sphere_mesh(b, "mirror sphere", chrome, 2, [0.8, 0.5, 0.3], 0.5)}))
    b.gltf["cameras"] = [{
        "name": "main",
        "type": "perspective",
        "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.01, "zfar": 100.0},
    }]
    eye = [0.0, 2.2, 5.0]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": eye,
                         "rotation": look_at_rotation(eye, [0.0, 0.4, 0.0])}))
    return nodes


def lights_showcase(path):
    b = Builder()
    b.gltf["extensionsUsed"] = ["KHR_lights_punctual"]
    nodes = lights_floor_and_spheres(b)
    glow = b.material({"name": "glow", "emissiveFactor": [1.0, 1.0, 1.0], "pbrMetallicRoughness": {"metallicFactor": 0.0},
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}})
    b.gltf["extensionsUsed"].append("KHR_materials_emissive_strength")
    quad = quad_mesh(b, "glow quad", glow, [[-2.5, 0.01, -2.0], [-2.5, 1.01, -2.0], [-2.5, 1.01, -1.0], [-2.5, 0.01, -1.0]])
    nodes.append(b.node({"name": "glow quad", "mesh": quad}))
    b.gltf["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "point", "type": "point", "color": [1.0, 0.8, 0.6], "intensity": 3.0, "range": 4.0},
        {"name": "spot", "type": "spot", "color": [0.6, 0.8, 1.0], "intensity": 20.0,
         "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.45}},
        {"name": "sphere", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 2.0,
         "extras": {"vkpt": {"radius": 0.15}}},
        {"name": "sun", "type": "directional", "color": [1.0, 0.95, 0.85], "intensity": 1.5,
         "extras": {"vkpt": {"angular_diameter": 0.05}}},
        {"name": "directional", "type": "directional", "color": [0.3, 0.3, 0.5], "intensity": 0.5},
    ]}}
    light = lambda i: {"KHR_lights_punctual": {"light": i}}
    nodes.append(b.node({"name": "point", "translation": [1.5, 1.2, 1.5], "extensions": light(0)}))
    spot_eye = [-1.0, 3.0, 1.5]
    nodes.append(b.node({"name": "spot", "translation": spot_eye, "rotation": look_at_rotation(spot_eye, [-0.7, 0.0, 0.0]),
                         "extensions": light(1)}))
    nodes.append(b.node({"name": "sphere", "translation": [0.2, 1.6, -1.0], "extensions": light(2)}))
    sun_from = [3.0, 4.0, 2.0]
    nodes.append(b.node({"name": "sun", "translation": sun_from, "rotation": look_at_rotation(sun_from, [0.0, 0.0, 0.0]),
                         "extensions": light(3)}))
    dir_from = [-3.0, 2.0, -1.0]
    nodes.append(b.node({"name": "directional", "translation": dir_from,
                         "rotation": look_at_rotation(dir_from, [0.0, 0.0, 0.0]), "extensions": light(4)}))
    b.gltf["scenes"].append({"name": "lights-showcase", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [0.03, 0.03, 0.04]}}})
    b.finish(path)


def env_sky(path):
    b = Builder()
    nodes = lights_floor_and_spheres(b)
    b.gltf["scenes"].append({"name": "env-sky", "nodes": nodes,
                             "extras": {"vkpt": {"environment_map": "env/sky-with-sun.exr"}}})
    b.finish(path)


# --------------------------------------------------------------------------
# Depth of field: an in-focus subject between out-of-focus bright spots.

def quad_facing_camera(centre, half, normal_z=1.0):
    """A square of half-size `half` in the XY plane at `centre`, front face
    toward +Z (toward the camera)."""
    x, y, z = centre
    q = [[x - half, y - half, z], [x + half, y - half, z], [x + half, y + half, z], [x - half, y + half, z]]
    return [q[0], q[1], q[2]], [q[0], q[2], q[3]]


def depth_of_field(path):
    b = Builder()
    b.gltf["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    grey = b.material(lambert("floor grey", [0.4, 0.4, 0.4]))
    orange = b.material(lambert("subject orange", [0.8, 0.35, 0.08]))

    def emissive(name, rgb, strength):
        m = lambert(name, [0.0, 0.0, 0.0])
        m["emissiveFactor"] = rgb
        m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        return b.material(m)

    overhead = emissive("overhead light", [1.0, 0.95, 0.9], 4.0)
    spot_colours = [[1.0, 0.85, 0.6], [0.6, 0.8, 1.0], [1.0, 0.6, 0.7]]
    spots = [emissive("spot %d" % i, c, 400.0) for i, c in enumerate(spot_colours)]
    nodes = []

    # Floor: y = 0 from z = +4 to z = -16, 12 m wide, facing up.
    floor = [[-6.0, 0.0, 4.0], [6.0, 0.0, 4.0], [6.0, 0.0, -16.0], [-6.0, 0.0, -16.0]]
    positions = [floor[0], floor[1], floor[2], floor[0], floor[2], floor[3]]
    n = normalize(cross(sub(positions[1], positions[0]), sub(positions[2], positions[0])))
    if n[1] < 0:
        positions = [floor[0], floor[2], floor[1], floor[0], floor[3], floor[2]]
        n = [0.0, 1.0, 0.0]
    nodes.append(b.node({"name": "floor", "mesh": b.mesh("floor", positions, [n] * 6, grey)}))

    # The subject: a sphere of radius 0.15 m resting on the floor at z = 0.
    mesh = sphere_mesh(b, "subject", orange, 3, [0.0, 0.15, 0.0], 0.15)
    nodes.append(b.node({"name": "subject", "mesh": mesh}))

    # Overhead area light: 2 m square at y = 3, facing down.
    light = [[-1.0, 3.0, -1.0], [1.0, 3.0, -1.0], [1.0, 3.0, 1.0], [-1.0, 3.0, 1.0]]
    positions = [light[0], light[1], light[2], light[0], light[2], light[3]]
    n = normalize(cross(sub(positions[1], positions[0]), sub(positions[2], positions[0])))
    if n[1] > 0:
        positions = [light[0], light[2], light[1], light[0], light[3], light[2]]
        n = [0.0, -1.0, 0.0]
    nodes.append(b.node({"name": "overhead light", "mesh": b.mesh("overhead light", positions, [n] * 6, overhead)}))

    # Bright spots, 2 cm squares facing the camera: far behind the subject
    # (z from -4 to -12) and a few in front of it (z = 1.2).
    spot_places = [
        ([-1.6, 0.9, -6.0], 0), ([-0.7, 1.3, -9.0], 1), ([0.5, 1.1, -7.0], 2), ([1.5, 0.6, -5.0], 0),
        ([2.4, 1.6, -12.0], 1), ([-2.5, 1.9, -12.0], 2), ([0.9, 0.35, -4.0], 1), ([-1.2, 0.4, -4.5], 2),
        ([0.1, 2.2, -11.0], 0), ([1.9, 2.4, -10.0], 2),
        ([-0.19, 0.2, 1.2], 0), ([0.21, 0.4, 1.2], 1),
    ]
    by_colour = {0: ([], []), 1: ([], []), 2: ([], [])}
    for centre, colour in spot_places:
        for tri in quad_facing_camera(centre, 0.01):
            by_colour[colour][0].extend([[round(c, 7) for c in p] for p in tri])
            by_colour[colour][1].extend([[0.0, 0.0, 1.0]] * 3)
    for colour, (pos, nor) in by_colour.items():
        mesh = b.mesh("spots %d" % colour, pos, nor, spots[colour])
        nodes.append(b.node({"name": "spots %d" % colour, "mesh": mesh}))

    # An 85 mm f/1.2 lens focused on the subject (2.5 m), six blades: the
    # yfov is what an 85 mm lens sees on a 24 mm sensor.
    focal, sensor = 0.085, 0.024
    b.gltf["cameras"] = [
        {
            "name": "main",
            "type": "perspective",
            "perspective": {"yfov": 2.0 * math.atan(0.5 * sensor / focal), "aspectRatio": 1.5,
                            "znear": 0.01, "zfar": 100.0},
            "extras": {"vkpt": {"lens": {"focal_length": focal, "sensor_height": sensor, "fstop": 1.2,
                                         "focus_distance": 2.5, "blades": 6, "blade_rotation": 0}}},
        },
        {
            "name": "ortho",
            "type": "orthographic",
            "orthographic": {"xmag": 0.6, "ymag": 0.4, "znear": 0.01, "zfar": 100.0},
        },
    ]
    nodes.append(b.node({"name": "main camera", "camera": 0, "translation": [0.0, 0.3, 2.5]}))
    # The orthographic camera looks down at 30 degrees onto the subject from
    # 3 m away (turned -30 degrees about +X).
    tilt = math.radians(-30.0)
    forward = [0.0, math.sin(tilt), -math.cos(tilt)]
    nodes.append(b.node({
        "name": "ortho camera",
        "camera": 1,
        "translation": [round(c, 7) for c in sub([0.0, 0.15, 0.0], scale(forward, 3.0))],
        "rotation": [round(math.sin(0.5 * tilt), 7), 0.0, 0.0, round(math.cos(0.5 * tilt), 7)],
    }))
    # A spherical light beside the subject (a point light with a radius),
    # and the bundled sky map lighting everything, dimmed.
    b.gltf["extensionsUsed"].append("KHR_lights_punctual")
    b.gltf["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "sphere light", "type": "point", "color": [1.0, 0.85, 0.7], "intensity": 0.6,
         "extras": {"vkpt": {"radius": 0.06}}},
    ]}}
    nodes.append(b.node({"name": "sphere light", "translation": [0.55, 0.55, 0.45],
                         "extensions": {"KHR_lights_punctual": {"light": 0}}}))
    b.gltf["scenes"].append({"name": "depth-of-field", "nodes": nodes,
                             "extras": {"vkpt": {"environment_map": "env/sky-with-sun.exr",
                                                 "environment": [0.25, 0.25, 0.25]}}})
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


def textured_terrain(path):
    """DamagedHelmet-class work for the speed benchmarks (issue 13): one
    textured mesh of 105,800 triangles (a 230 x 230 height field with analytic
    normals and a repeating checker), under a light panel and a dim sky."""
    b = TexturedBuilder()
    b.gltf["extensionsUsed"] = ["KHR_texture_transform"]
    checker = b.texture(checker_rows(8, 1, (200, 170, 110, 255), (70, 110, 60, 255)),
                        {"magFilter": LINEAR, "wrapS": REPEAT, "wrapT": REPEAT}, "terrain checker", True)
    ground = b.material({
        "name": "terrain",
        "pbrMetallicRoughness": {
            "baseColorTexture": {"index": checker, "extensions": {
                "KHR_texture_transform": {"scale": [6.0, 6.0]}}},
            "metallicFactor": 0.0, "roughnessFactor": 0.8},
    })
    n = 230
    size = 4.0

    def height(x, z):
        return 0.25 * math.sin(2.1 * x) * math.cos(1.7 * z) + 0.08 * math.sin(5.3 * x + 1.1) * math.sin(4.7 * z)

    def gradient(x, z):
        hx = 0.25 * 2.1 * math.cos(2.1 * x) * math.cos(1.7 * z) + 0.08 * 5.3 * math.cos(5.3 * x + 1.1) * math.sin(4.7 * z)
        hz = -0.25 * 1.7 * math.sin(2.1 * x) * math.sin(1.7 * z) + 0.08 * 4.7 * math.sin(5.3 * x + 1.1) * math.cos(4.7 * z)
        return hx, hz

    positions, normals, uvs = [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            x = -size / 2 + size * i / n
            z = -size / 2 + size * j / n
            positions.append([x, height(x, z), z])
            hx, hz = gradient(x, z)
            normals.append(normalize([-hx, 1.0, -hz]))
            uvs.append([i / n, j / n])
    indices = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            # Counter-clockwise seen from above (+Y).
            indices += [a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]
    prim = {
        "attributes": {
            "POSITION": b.vec3_accessor(positions, True),
            "NORMAL": b.vec3_accessor(normals, False),
            "TEXCOORD_0": b.accessor(uvs, "VEC2", "2f"),
        },
        "indices": b.index_accessor(indices),
        "material": ground,
        "mode": 4,
    }
    b.gltf["meshes"].append({"name": "terrain", "primitives": [prim]})
    light = b.material({
        "name": "light panel",
        "emissiveFactor": [1.0, 0.95, 0.85],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6.0}},
        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
    })
    nodes = [
        b.node({"name": "terrain", "mesh": len(b.gltf["meshes"]) - 1}),
        b.quad("light", [[-0.8, 2.5, -0.8], [0.8, 2.5, -0.8], [0.8, 2.5, 0.8], [-0.8, 2.5, 0.8]], light),
    ]
    nodes.append(look_down_camera(b, [0.0, 2.2, 3.6], math.atan2(2.0, 3.6)))
    b.gltf["scenes"].append({"name": "textured terrain", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [0.08, 0.1, 0.14]}}})
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


def clearcoat(name, base, metallic, roughness, factor, coat_roughness, extensions=None):
    ext = dict(extensions or {})
    ext["KHR_materials_clearcoat"] = {"clearcoatFactor": factor, "clearcoatRoughnessFactor": coat_roughness}
    return pbr(name, base, metallic, roughness, ext)


def anisotropic(name, base, metallic, roughness, strength, rotation=0.0, extensions=None):
    ext = dict(extensions or {})
    aniso = {"anisotropyStrength": strength}
    if rotation:
        aniso["anisotropyRotation"] = rotation
    ext["KHR_materials_anisotropy"] = aniso
    return pbr(name, base, metallic, roughness, ext)


def add_sphere_tangents(b, mesh):
    """TANGENTs around the vertical axis (w = 1) for an icosphere mesh
    centred where its positions' bounds are; x at the poles."""
    prim = b.gltf["meshes"][mesh]["primitives"][0]
    acc = b.gltf["accessors"][prim["attributes"]["POSITION"]]
    centre = [(acc["min"][i] + acc["max"][i]) / 2.0 for i in range(3)]
    view = b.gltf["bufferViews"][acc["bufferView"]]
    data = b.data[view["byteOffset"]:view["byteOffset"] + view["byteLength"]]
    tangents = []
    for k in range(acc["count"]):
        p = struct.unpack_from("<3f", data, 12 * k)
        d = sub(p, centre)
        t = [d[2], 0.0, -d[0]]
        length = math.sqrt(dot(t, t))
        tangents.append([t[0] / length, 0.0, t[2] / length, 1.0] if length > 1e-6 else [1.0, 0.0, 0.0, 1.0])
    blob = b"".join(struct.pack("<4f", *t) for t in tangents)
    b.gltf["accessors"].append({"bufferView": b._view(blob, 34962), "componentType": 5126,
                                "count": len(tangents), "type": "VEC4"})
    prim["attributes"]["TANGENT"] = len(b.gltf["accessors"]) - 1


def coat_grid(path):
    b = Builder()
    nodes = []
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
    glass = {"KHR_materials_transmission": {"transmissionFactor": 1.0},
             "KHR_materials_volume": {"thicknessFactor": 1.0}}
    materials = [
        clearcoat("rough coat over red plastic", [0.6, 0.08, 0.05], 0.0, 0.5, 1.0, 0.3),
        clearcoat("smooth coat over rough gold", [1.0, 0.78, 0.34], 1.0, 0.5, 0.8, 0.0),
        clearcoat("smooth coat over smooth metal", [0.9, 0.9, 0.9], 1.0, 0.0, 1.0, 0.0),
        clearcoat("coat over anisotropic blue", [0.1, 0.2, 0.6], 0.0, 0.4, 1.0, 0.2,
                  {"KHR_materials_anisotropy": {"anisotropyStrength": 0.8}}),
        anisotropic("anisotropic steel", [0.9, 0.9, 0.9], 1.0, 0.3, 0.8),
        anisotropic("anisotropic copper, rotated", [0.95, 0.64, 0.54], 1.0, 0.3, 0.7, 1.0),
        anisotropic("anisotropic rough glass", [1.0, 1.0, 1.0], 0.0, 0.3, 0.6, 0.0, glass),
        anisotropic("anisotropic metal, roughness 0", [0.9, 0.9, 0.9], 1.0, 0.0, 0.5),
    ]
    for k, m in enumerate(materials):
        centre = [-1.5 + (k % 4), 0.5 - (k // 4), 0.0]
        mesh = sphere_mesh(b, "sphere %d" % k, b.material(m), 3, centre, 0.42)
        add_sphere_tangents(b, mesh)
        nodes.append(b.node({"name": "sphere %d" % k, "mesh": mesh}))
    half_height = 1.2
    b.gltf["cameras"] = [{
        "name": "main",
        "type": "perspective",
        "perspective": {"yfov": 2.0 * math.atan(half_height / 6.0), "aspectRatio": 2.0,
                        "znear": 0.01, "zfar": 100.0},
    }]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.0, 6.0]}))
    b.gltf["scenes"].append({
        "name": "coat-grid",
        "nodes": nodes,
        "extras": {"vkpt": {"environment": [0.3, 0.3, 0.3]}},
    })
    b.finish(path)


# --------------------------------------------------------------------------
# Read back and check what the spec requires.

# --------------------------------------------------------------------------
# Animated scenes (scenes/animated/): keyframes for --time, --frames and
# motion blur.

def float_accessor(b, values, kind):
    """A float accessor of type kind ("SCALAR", "VEC3", "VEC4") with its
    bounds (glTF requires them on animation inputs)."""
    n = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[kind]
    flat = [float(x) for v in values for x in (v if n > 1 else [v])]
    blob = struct.pack("<%df" % len(flat), *flat)
    stored = struct.unpack("<%df" % len(flat), blob)
    acc = {
        "bufferView": b._view(blob, None),
        "componentType": 5126,
        "count": len(values),
        "type": kind,
        "min": [min(stored[i::n]) for i in range(n)],
        "max": [max(stored[i::n]) for i in range(n)],
    }
    del b.gltf["bufferViews"][acc["bufferView"]]["target"]
    b.gltf["accessors"].append(acc)
    return len(b.gltf["accessors"]) - 1


def animation(b, name, node, path, times, values, interpolation="LINEAR"):
    kind = {"translation": "VEC3", "scale": "VEC3", "rotation": "VEC4"}[path]
    sampler = {"input": float_accessor(b, times, "SCALAR"), "output": float_accessor(b, values, kind),
               "interpolation": interpolation}
    b.gltf.setdefault("animations", []).append({
        "name": name,
        "samplers": [sampler],
        "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
    })


def moving_square(path):
    """A white emissive square (radiance 1) of side 0.5 crossing a black
    background at constant speed: x from -1 to +1 between t = 0 and 1 s, in
    the plane z = 0, seen head-on by a camera at z = 4 (vertical field of
    view 2·atan(0.5), so the view is 4 units wide and high at z = 0)."""
    b = Builder()
    white = b.material({"name": "white light", "emissiveFactor": [1.0, 1.0, 1.0],
                        "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}})
    t1, t2 = quad_facing_camera([0.0, 0.0, 0.0], 0.25)
    mesh = b.mesh("square", t1 + t2, [[0.0, 0.0, 1.0]] * 6, white)
    square = b.node({"name": "square", "mesh": mesh, "translation": [-1.0, 0.0, 0.0]})
    b.gltf["cameras"] = [perspective("camera", math.degrees(2 * math.atan(0.5)))]
    camera = b.node({"name": "camera", "camera": 0, "translation": [0.0, 0.0, 4.0]})
    animation(b, "slide", square, "translation", [0.0, 1.0], [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    b.gltf["scenes"].append({"name": "moving-square", "nodes": [square, camera],
                             "extras": {"vkpt": {"environment": [0.0, 0.0, 0.0]}}})
    b.finish(path)


def interpolation_test(path):
    """Three cubes rising and falling over 0..2 s (y from 0.25 to 1.75 and
    back, keyframes at 0, 1 and 2 s), with STEP, LINEAR and CUBICSPLINE
    interpolation (the spline's tangents are +3 and -3 units/s on the way
    up and down), and a fourth turning 90° about Y per second (LINEAR:
    slerp), on a grey floor under a white environment: vkpt's stand-in for
    Khronos' InterpolationTest, whose binary buffer the tools here cannot
    fetch."""
    b = Builder()
    floor = b.material(lambert("floor", [0.5, 0.5, 0.5]))
    nodes = [b.node({"name": "floor", "mesh": quad_mesh(b, "floor", floor, [[-4, 0, 3], [4, 0, 3], [4, 0, -3], [-4, 0, -3]])})]
    colours = {"step": [0.8, 0.2, 0.2], "linear": [0.2, 0.8, 0.2], "cubicspline": [0.2, 0.3, 0.9], "turn": [0.8, 0.8, 0.2]}
    for i, (name, rgb) in enumerate(colours.items()):
        node = add_box(b, name, b.material(lambert(name, rgb)), [-0.25, -0.25, -0.25], [0.25, 0.25, 0.25])
        b.gltf["nodes"][node]["translation"] = [-2.25 + 1.5 * i, 0.25, 0.0]
        nodes.append(node)
        x = -2.25 + 1.5 * i
        if name == "step":
            animation(b, name, node, "translation", [0.0, 1.0, 2.0], [[x, 0.25, 0], [x, 1.75, 0], [x, 0.25, 0]], "STEP")
        elif name == "linear":
            animation(b, name, node, "translation", [0.0, 1.0, 2.0], [[x, 0.25, 0], [x, 1.75, 0], [x, 0.25, 0]])
        elif name == "cubicspline":
            z = [0.0, 0.0, 0.0]
            keys = [z, [x, 0.25, 0], [0, 3, 0], z, [x, 1.75, 0], [0, -3, 0], z, [x, 0.25, 0], z]
            animation(b, name, node, "translation", [0.0, 1.0, 2.0], keys, "CUBICSPLINE")
        else:
            s45 = math.sqrt(0.5)
            animation(b, name, node, "rotation", [0.0, 1.0, 2.0], [[0, 0, 0, 1], [0, s45, 0, s45], [0, 1, 0, 0]])
    b.gltf["cameras"] = [perspective("camera", 40.0, 2.0)]
    eye = [0.0, 2.5, 6.5]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": eye,
                         "rotation": look_at_rotation(eye, [0.0, 0.8, 0.0])}))
    b.gltf["scenes"].append({"name": "interpolation-test", "nodes": nodes,
                             "extras": {"vkpt": {"environment": [1.0, 1.0, 1.0]}}})
    b.finish(path)


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


def emissive(name, rgb, strength):
    m = lambert(name, [0.0, 0.0, 0.0])
    m["emissiveFactor"] = rgb
    m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
    return m


def quads_mesh(b, name, material, quads):
    """One mesh of many quads (two triangles each, no index buffer: more
    vertices than 16-bit indices reach)."""
    positions, normals = [], []
    for q in quads:
        n = normalize(cross(sub(q[1], q[0]), sub(q[2], q[0])))
        for tri in ([q[0], q[1], q[2]], [q[0], q[2], q[3]]):
            positions.extend(tri)
            normals.extend([n, n, n])
    return b.node({"name": name, "mesh": b.mesh(name, positions, normals, material)})


def hall_lamps(path, rooms=6, per_side=6, room=4.0, height=3.0):
    """Many lights behind walls (the light BVH's test scene): a hall of
    rooms x rooms rooms of room x room metres, split by partition walls
    with a door 1 m wide in each, every room lit by per_side^2 small
    one-sided ceiling lamps (two triangles each) of six colours and
    radiances spread over two decades; the camera stands in one room,
    looking through its door. 6 x 6 rooms of 36 lamps: 2,592 emissive
    triangles, most hidden from any one point."""
    import random
    rng = random.Random(50)
    b = Builder()
    b.gltf["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    grey = b.material(lambert("walls", [0.6, 0.6, 0.6]))
    floor_mat = b.material(lambert("floor", [0.4, 0.35, 0.3]))
    colours = [[1.0, 0.85, 0.6], [0.6, 0.8, 1.0], [1.0, 0.5, 0.4], [0.5, 1.0, 0.6], [1.0, 1.0, 1.0], [0.9, 0.6, 1.0]]
    levels = [1.0, 4.64, 21.5, 100.0]
    lamp_mats = [[b.material(emissive("lamp %d/%d" % (c, l), colours[c], 2.0 * levels[l]))
                  for l in range(len(levels))] for c in range(len(colours))]
    size = rooms * room
    nodes = [add_box(b, "floor", floor_mat, [0.0, -0.1, 0.0], [size, 0.0, size]),
             add_box(b, "ceiling", grey, [0.0, height, 0.0], [size, height + 0.1, size])]
    for side, (lo, hi) in enumerate([([-0.1, 0.0, 0.0], [0.0, height, size]),
                                     ([size, 0.0, 0.0], [size + 0.1, height, size]),
                                     ([0.0, 0.0, -0.1], [size, height, 0.0]),
                                     ([0.0, 0.0, size], [size, height, size + 0.1])]):
        nodes.append(add_box(b, "outer wall %d" % side, grey, lo, hi))
    # Partition walls: a 1 m door in the middle of each room's stretch.
    t, door = 0.05, 0.5
    for i in range(1, rooms):
        c = i * room
        for j in range(rooms):
            a, m, e = j * room, j * room + 0.5 * room, (j + 1) * room
            for k, (u0, u1) in enumerate([(a, m - door), (m + door, e)]):
                nodes.append(add_box(b, "wall x %d %d %d" % (i, j, k), grey, [c - t, 0.0, u0], [c + t, height, u1]))
                nodes.append(add_box(b, "wall z %d %d %d" % (i, j, k), grey, [u0, 0.0, c - t], [u1, height, c + t]))
    lamps = {}
    h = 0.075
    y = height - 0.001
    for rx in range(rooms):
        for rz in range(rooms):
            for a in range(per_side):
                for c in range(per_side):
                    x = rx * room + (a + 0.5 + rng.uniform(-0.3, 0.3)) * room / per_side
                    z = rz * room + (c + 0.5 + rng.uniform(-0.3, 0.3)) * room / per_side
                    key = (rng.randrange(len(colours)), rng.randrange(len(levels)))
                    # Facing down: counter-clockwise seen from below.
                    lamps.setdefault(key, []).append(
                        [[x - h, y, z - h], [x + h, y, z - h], [x + h, y, z + h], [x - h, y, z + h]])
    for (ci, li), quads in sorted(lamps.items()):
        nodes.append(quads_mesh(b, "lamps %d/%d" % (ci, li), lamp_mats[ci][li], quads))
    b.gltf["cameras"] = [perspective("main", 60.0)]
    eye = [2.5 * room + 0.6, 1.6, 2.5 * room + 1.2]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": eye,
                         "rotation": look_at_rotation(eye, [2.0 * room + 0.5 * room, 1.2, 2.0 * room - 0.5])}))
    b.gltf["scenes"].append({"name": "hall-lamps", "nodes": nodes})
    b.finish(path)


def night_street(path, blocks=24, floors=6, per_floor=8):
    """Thousands of emissive triangles in one mesh (the light BVH's second
    test scene): a street 4 * blocks metres long between two rows of
    buildings whose lit windows are one emissive mesh (two triangles a
    window; the windows' sizes vary), seen from the pavement at one end."""
    import random
    rng = random.Random(51)
    b = Builder()
    b.gltf["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    facade = b.material(lambert("facades", [0.5, 0.45, 0.4]))
    road = b.material(lambert("road", [0.2, 0.2, 0.2]))
    glow = b.material(emissive("windows", [1.0, 0.8, 0.55], 20.0))
    length = 4.0 * blocks
    width = 6.0
    nodes = [add_box(b, "road", road, [-width - 2.0, -0.1, -2.0], [width + 2.0, 0.0, length + 2.0])]
    windows = []
    for side in (-1.0, 1.0):
        for k in range(blocks):
            z0, z1 = 4.0 * k + 0.1, 4.0 * (k + 1) - 0.1
            top = 3.0 * floors * rng.uniform(0.6, 1.0)
            x0, x1 = (width, width + 6.0) if side > 0 else (-width - 6.0, -width)
            nodes.append(add_box(b, "building %d %d" % (side > 0, k), facade, [x0, 0.0, z0], [x1, top, z1]))
            xf = x0 - 0.01 if side > 0 else x1 + 0.01
            for f in range(int(top / 3.0)):
                for w in range(per_floor):
                    if rng.random() < 0.3:
                        continue  # a dark window
                    zc = z0 + (w + 0.5) * (z1 - z0) / per_floor
                    hw = rng.uniform(0.05, 0.2)
                    hh = rng.uniform(0.3, 0.8)
                    yc = 3.0 * f + 1.5
                    q = [[xf, yc - hh, zc - hw], [xf, yc - hh, zc + hw], [xf, yc + hh, zc + hw], [xf, yc + hh, zc - hw]]
                    if side < 0:
                        q.reverse()  # face +x, toward the street
                    windows.append(q)
    nodes.append(quads_mesh(b, "windows", glow, windows))
    b.gltf["cameras"] = [perspective("main", 55.0, 1.5)]
    eye = [-2.0, 1.7, -1.0]
    nodes.append(b.node({"name": "camera", "camera": 0, "translation": eye,
                         "rotation": look_at_rotation(eye, [0.5, 4.0, 30.0])}))
    b.gltf["scenes"].append({"name": "night-street", "nodes": nodes})
    b.finish(path)


def main():
    outputs = [
        (os.path.join(HERE, "cornell-box.gltf"), cornell_box),
        (os.path.join(HERE, "white-furnace.gltf"), white_furnace),
        (os.path.join(HERE, "furnace-glass-1.5.gltf"),
         lambda p: white_furnace(p, glass_volume("glass ior 1.5", 1.5))),
        (os.path.join(HERE, "furnace-glass-0.67.gltf"), lambda p: white_furnace(p, bubble("bubble ior 0.67", 0.67))),
        (os.path.join(HERE, "furnace-mirror-0.8.gltf"), lambda p: white_furnace(p, mirror("mirror 0.8", [0.8, 0.8, 0.8]))),
        (os.path.join(HERE, "materials-showcase.gltf"), lambda p: cornell_box(p, showcase=True)),
        (os.path.join(HERE, "cornell-spheres.gltf"), lambda p: cornell_box(p, glass_and_mirror=True)),
        (os.path.join(HERE, "lights-showcase.gltf"), lights_showcase),
        (os.path.join(HERE, "env-sky.gltf"), env_sky),
        (os.path.join(HERE, "depth-of-field.gltf"), depth_of_field),
        (os.path.join(HERE, "materials-grid.gltf"), materials_grid),
        (os.path.join(HERE, "furnace-rough-metal.gltf"),
         lambda p: white_furnace(p, pbr("white rough metal", [1.0, 1.0, 1.0], 1.0, 1.0), subdivisions=5)),
        (os.path.join(HERE, "furnace-clearcoat.gltf"),
         lambda p: white_furnace(p, clearcoat("white coat over white diffuse", [1.0, 1.0, 1.0], 0.0, 1.0, 1.0, 0.5,
                                              {"KHR_materials_specular": {"specularFactor": 0.0}}),
                                 subdivisions=5)),
        (os.path.join(HERE, "coat-grid.gltf"), coat_grid),
        (os.path.join(HERE, "textured.gltf"), textured_scene),
        (os.path.join(HERE, "textured-terrain.gltf"), textured_terrain),
        (os.path.join(HERE, "alpha-mask.gltf"), lambda p: alpha_scene(p, False)),
        (os.path.join(HERE, "alpha-holes.gltf"), lambda p: alpha_scene(p, True)),
        (os.path.join(HERE, "hall-lamps.gltf"), hall_lamps),
        (os.path.join(HERE, "night-street.gltf"), night_street),
    ]
    outputs += hard_cases()  # after cornell-box.gltf: three of them are made from it
    os.makedirs(os.path.join(HERE, "animated"), exist_ok=True)
    outputs += [(os.path.join(HERE, "animated", "moving-square.gltf"), moving_square),
                (os.path.join(HERE, "animated", "interpolation-test.gltf"), interpolation_test)]
    for path, build in outputs:
        build(path)
        validate(path)
        print("wrote and checked", os.path.relpath(path))


if __name__ == "__main__":
    main()
