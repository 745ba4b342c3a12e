#!/usr/bin/env python3
"""Generates the two built-in scenes of fuzzy-vpl as binary glTF 2.0 files.

    python3 assets/generate_scenes.py

writes assets/cornell.glb and assets/conference.glb next to this script. Python 3 standard library
only; the output is byte-for-byte deterministic (no timestamps, no randomness, Python's shortest
round-trip float formatting).

All geometry is generated here. The Cornell box uses the published measurements of the Cornell
Program of Computer Graphics ("Cornell Box data" page), converted from millimetres to metres; the
conference room is an original layout. See assets/README.md.
"""

import json
import math
import os
import struct

# Emissive strength (KHR_materials_emissive_strength) of the Cornell box ceiling light. The emitted
# radiance is emissiveFactor (max component 1) times this value. Knob for the overall light level.
CORNELL_LIGHT_STRENGTH = 27.0

# Emissive strength of each of the conference room's ceiling panels.
CONFERENCE_LIGHT_STRENGTH = 8.0

GENERATOR = "fuzzy-vpl assets/generate_scenes.py"

ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
FLOAT = 5126
UNSIGNED_SHORT = 5123
UNSIGNED_INT = 5125
TRIANGLES = 4


# ---------------------------------------------------------------------------------------------
# Small vector helpers (tuples of floats)
# ---------------------------------------------------------------------------------------------

def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def centroid(pts):
    s = (0.0, 0.0, 0.0)
    for p in pts:
        s = add(s, p)
    return scale(s, 1.0 / len(pts))


def f32(x):
    """Rounds a Python float to the nearest float32 (what ends up in the buffer)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def quat_from_axes(x_axis, y_axis, z_axis):
    """Unit quaternion [x, y, z, w] of the rotation whose matrix columns are the given axes."""
    m00, m10, m20 = x_axis
    m01, m11, m21 = y_axis
    m02, m12, m22 = z_axis
    tr = m00 + m11 + m22
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2.0
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2.0
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2.0
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    n = math.sqrt(sum(c * c for c in q))
    q = tuple(c / n for c in q)
    if q[3] < 0.0:
        q = tuple(-c for c in q)
    return [stable(c) for c in q]


def stable(x):
    """Rounds a value that went through libm (sin, cos, atan, ...) to 12 decimals, so that a one-ulp
    difference between C libraries cannot change the written bytes; also turns -0.0 into 0.0."""
    return round(x, 12) + 0.0


def quat_yaw(degrees):
    """Rotation about +Y by `degrees` (right-handed: +90 turns +Z into +X)."""
    h = math.radians(degrees) * 0.5
    return [0.0, stable(math.sin(h)), 0.0, stable(math.cos(h))]


def look_rotation(eye, target, up=(0.0, 1.0, 0.0)):
    """Quaternion turning a glTF camera (looks down local -Z, +Y up) at `target` from `eye`."""
    fwd = normalize(sub(target, eye))
    right = normalize(cross(fwd, up))
    true_up = cross(right, fwd)
    return quat_from_axes(right, true_up, scale(fwd, -1.0))


# ---------------------------------------------------------------------------------------------
# Geometry: polygons with flat normals, collected into one primitive's vertex/index lists
# ---------------------------------------------------------------------------------------------

class Geometry:
    """Flat-shaded triangles for one mesh primitive (one material)."""

    def __init__(self):
        self.positions = []
        self.normals = []
        self.indices = []

    def triangle_count(self):
        return len(self.indices) // 3

    def _emit(self, pts, n):
        base = len(self.positions)
        for p in pts:
            self.positions.append(p)
            self.normals.append(n)
        for i in range(1, len(pts) - 1):
            self.indices.extend((base, base + i, base + i + 1))

    def polygon(self, pts, toward):
        """Adds a convex polygon (3 or 4 points, any order around the boundary) facing `toward`.

        The winding is made counter-clockwise when seen from the side the normal points to, and the
        normal is the polygon's unit face normal oriented to have a positive dot product with
        `toward`. A non-planar quad is split into two triangles, each with its own exact normal."""
        pts = list(pts)
        # Newell normal of the whole polygon decides the orientation.
        nx = ny = nz = 0.0
        for i, p in enumerate(pts):
            q = pts[(i + 1) % len(pts)]
            nx += (p[1] - q[1]) * (p[2] + q[2])
            ny += (p[2] - q[2]) * (p[0] + q[0])
            nz += (p[0] - q[0]) * (p[1] + q[1])
        if dot((nx, ny, nz), toward) < 0.0:
            pts.reverse()
        if len(pts) == 3:
            self._emit(pts, normalize(cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))))
            return
        assert len(pts) == 4
        n0 = normalize(cross(sub(pts[1], pts[0]), sub(pts[2], pts[0])))
        n1 = normalize(cross(sub(pts[2], pts[0]), sub(pts[3], pts[0])))
        if dot(n0, n1) > 1.0 - 1e-12:
            self._emit(pts, normalize(add(n0, n1)))
        else:
            self._emit([pts[0], pts[1], pts[2]], n0)
            self._emit([pts[0], pts[2], pts[3]], n1)

    def box(self, lo, hi, omit=()):
        """Axis-aligned closed box with outward normals; `omit` names faces to leave out
        ("-x", "+x", "-y", "+y", "-z", "+z"), e.g. "-y" for a bottom resting on the floor."""
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        faces = {
            "-x": ([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1.0, 0.0, 0.0)),
            "+x": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1.0, 0.0, 0.0)),
            "-y": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0.0, -1.0, 0.0)),
            "+y": ([(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)], (0.0, 1.0, 0.0)),
            "-z": ([(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)], (0.0, 0.0, -1.0)),
            "+z": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0.0, 0.0, 1.0)),
        }
        for key in ("-x", "+x", "-y", "+y", "-z", "+z"):
            if key not in omit:
                pts, n = faces[key]
                self.polygon(pts, n)


# ---------------------------------------------------------------------------------------------
# glTF / GLB writer
# ---------------------------------------------------------------------------------------------

class GltfBuilder:
    def __init__(self):
        self.pos_bytes = bytearray()
        self.nrm_bytes = bytearray()
        self.idx_bytes = bytearray()
        self.accessors = []  # (dict, view-name) pairs; bufferView filled in at the end
        self.meshes = []
        self.materials = []
        self.nodes = []
        self.cameras = []
        self.scene_nodes = []
        self.uses_emissive_strength = False

    # -- materials ------------------------------------------------------------------------
    def material(self, name, base_rgb, emissive_rgb=None, emissive_strength=None):
        m = {
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [base_rgb[0], base_rgb[1], base_rgb[2], 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            },
        }
        if emissive_rgb is not None:
            mx = max(emissive_rgb)
            m["emissiveFactor"] = [round(c / mx, 6) for c in emissive_rgb]
            if emissive_strength is not None:
                strength = {"emissiveStrength": float(emissive_strength)}
                m["extensions"] = {"KHR_materials_emissive_strength": strength}
                self.uses_emissive_strength = True
        self.materials.append(m)
        return len(self.materials) - 1

    # -- meshes ---------------------------------------------------------------------------
    def _primitive(self, geo, material):
        count = len(geo.positions)
        assert count > 0 and geo.indices
        p_off = len(self.pos_bytes)
        lo = [math.inf] * 3
        hi = [-math.inf] * 3
        for p in geo.positions:
            q = [f32(c) for c in p]
            self.pos_bytes += struct.pack("<3f", *q)
            for k in range(3):
                lo[k] = min(lo[k], q[k])
                hi[k] = max(hi[k], q[k])
        n_off = len(self.nrm_bytes)
        for n in geo.normals:
            self.nrm_bytes += struct.pack("<3f", *n)
        i_off = len(self.idx_bytes)
        if count <= 65535:
            ctype, fmt = UNSIGNED_SHORT, "<H"
        else:
            ctype, fmt = UNSIGNED_INT, "<I"
        for i in geo.indices:
            self.idx_bytes += struct.pack(fmt, i)
        while len(self.idx_bytes) % 4:
            self.idx_bytes += b"\x00"
        a_pos = self._accessor("positions", p_off, FLOAT, count, "VEC3", lo, hi)
        a_nrm = self._accessor("normals", n_off, FLOAT, count, "VEC3")
        a_idx = self._accessor("indices", i_off, ctype, len(geo.indices), "SCALAR")
        return {
            "attributes": {"NORMAL": a_nrm, "POSITION": a_pos},
            "indices": a_idx,
            "material": material,
            "mode": TRIANGLES,
        }

    def _accessor(self, view, offset, ctype, count, atype, lo=None, hi=None):
        a = {"bufferView": view, "byteOffset": offset, "componentType": ctype,
             "count": count, "type": atype}
        if lo is not None:
            a["max"] = list(hi)
            a["min"] = list(lo)
        self.accessors.append(a)
        return len(self.accessors) - 1

    def mesh(self, name, parts):
        """`parts`: list of (Geometry, material index). Returns the mesh index."""
        prims = [self._primitive(g, m) for g, m in parts]
        self.meshes.append({"name": name, "primitives": prims})
        return len(self.meshes) - 1

    # -- nodes ----------------------------------------------------------------------------
    def node(self, name, mesh=None, camera=None, translation=None, rotation=None, children=None,
             root=True):
        n = {"name": name}
        if mesh is not None:
            n["mesh"] = mesh
        if camera is not None:
            n["camera"] = camera
        if children:
            n["children"] = list(children)
        if rotation is not None and rotation != [0.0, 0.0, 0.0, 1.0]:
            n["rotation"] = list(rotation)
        if translation is not None and list(translation) != [0.0, 0.0, 0.0]:
            n["translation"] = list(translation)
        self.nodes.append(n)
        idx = len(self.nodes) - 1
        if root:
            self.scene_nodes.append(idx)
        return idx

    def camera(self, name, yfov, aspect, znear, zfar):
        self.cameras.append({
            "name": name,
            "type": "perspective",
            "perspective": {"aspectRatio": aspect, "yfov": yfov, "zfar": zfar, "znear": znear},
        })
        return len(self.cameras) - 1

    # -- output ---------------------------------------------------------------------------
    def glb(self, scene_name):
        views = []
        binary = bytearray()
        view_index = {}
        for key, data, target, stride in (
            ("positions", self.pos_bytes, ARRAY_BUFFER, 12),
            ("normals", self.nrm_bytes, ARRAY_BUFFER, 12),
            ("indices", self.idx_bytes, ELEMENT_ARRAY_BUFFER, None),
        ):
            assert len(binary) % 4 == 0
            v = {"buffer": 0, "byteOffset": len(binary), "byteLength": len(data)}
            if stride is not None:
                v["byteStride"] = stride
            v["target"] = target
            v["name"] = key
            view_index[key] = len(views)
            views.append(v)
            binary += data
            while len(binary) % 4:
                binary += b"\x00"
        accessors = []
        for a in self.accessors:
            a = dict(a)
            a["bufferView"] = view_index[a["bufferView"]]
            accessors.append(a)

        doc = {"asset": {"generator": GENERATOR, "version": "2.0"}}
        if self.uses_emissive_strength:
            doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
        doc["scene"] = 0
        doc["scenes"] = [{"name": scene_name, "nodes": self.scene_nodes}]
        doc["nodes"] = self.nodes
        doc["meshes"] = self.meshes
        doc["materials"] = self.materials
        if self.cameras:
            doc["cameras"] = self.cameras
        doc["accessors"] = accessors
        doc["bufferViews"] = views
        doc["buffers"] = [{"byteLength": len(binary)}]

        js = json.dumps(doc, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode()
        while len(js) % 4:
            js += b" "
        total = 12 + 8 + len(js) + 8 + len(binary)
        out = bytearray()
        out += struct.pack("<4sII", b"glTF", 2, total)
        out += struct.pack("<I4s", len(js), b"JSON") + js
        out += struct.pack("<I4s", len(binary), b"BIN\x00") + binary
        assert len(out) == total
        return bytes(out)


# ---------------------------------------------------------------------------------------------
# Scene 1: the Cornell box (published measurements, millimetres -> metres)
# ---------------------------------------------------------------------------------------------

MM = 0.001

# Vertices as published on the Cornell Box data page (millimetres). The published coordinates are
# right-handed as they stand: the camera at z = -800 looks toward +z with +y up, so its right hand
# points to -x, which puts the red wall (x ~ 550) on the LEFT and the green wall (x = 0) on the
# RIGHT of the image, as in the well-known renderings. No mirroring is needed.
CORNELL_FLOOR = [(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]
CORNELL_CEILING = [(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2),
                   (0.0, 548.8, 0.0)]
CORNELL_BACK_WALL = [(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2),
                     (556.0, 548.8, 559.2)]
CORNELL_RIGHT_WALL_GREEN = [(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0),
                            (0.0, 548.8, 559.2)]
CORNELL_LEFT_WALL_RED = [(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2),
                         (556.0, 548.8, 0.0)]
CORNELL_SHORT_BLOCK = [
    [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
    [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
    [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
    [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
    [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
]
CORNELL_TALL_BLOCK = [
    [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
    [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
    [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
    [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
    [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
]
# The published light lies in the ceiling plane (y = 548.8); it is lowered by 0.1 mm so that it does
# not coincide with the ceiling, and faces down.
CORNELL_LIGHT_Y = 548.7
CORNELL_LIGHT = [(343.0, CORNELL_LIGHT_Y, 227.0), (343.0, CORNELL_LIGHT_Y, 332.0),
                 (213.0, CORNELL_LIGHT_Y, 332.0), (213.0, CORNELL_LIGHT_Y, 227.0)]
CORNELL_CAMERA_POS = (278.0, 273.0, -800.0)
CORNELL_FOCAL = 0.035
CORNELL_FILM = 0.025


def mm(points):
    return [tuple(c * MM for c in p) for p in points]


def build_cornell():
    b = GltfBuilder()
    white = b.material("white", (0.73, 0.73, 0.73))
    red = b.material("red", (0.63, 0.065, 0.05))
    green = b.material("green", (0.14, 0.45, 0.091))
    light = b.material("light", (0.78, 0.78, 0.78), emissive_rgb=(1.0, 0.71, 0.24),
                       emissive_strength=CORNELL_LIGHT_STRENGTH)

    room_center = scale((278.0, 274.4, 279.6), MM)

    def room_face(name, pts, mat):
        g = Geometry()
        pts = mm(pts)
        g.polygon(pts, sub(room_center, centroid(pts)))  # normals point into the box
        b.node(name, mesh=b.mesh(name, [(g, mat)]))

    room_face("floor", CORNELL_FLOOR, white)
    room_face("ceiling", CORNELL_CEILING, white)
    room_face("back_wall", CORNELL_BACK_WALL, white)
    room_face("left_wall_red", CORNELL_LEFT_WALL_RED, red)
    room_face("right_wall_green", CORNELL_RIGHT_WALL_GREEN, green)

    def block(name, faces):
        g = Geometry()
        faces = [mm(f) for f in faces]
        corners = [p for f in faces for p in f]
        c = centroid(corners)
        for f in faces:
            g.polygon(f, sub(centroid(f), c))  # normals point out of the block
        b.node(name, mesh=b.mesh(name, [(g, white)]))

    block("short_block", CORNELL_SHORT_BLOCK)
    block("tall_block", CORNELL_TALL_BLOCK)

    g = Geometry()
    g.polygon(mm(CORNELL_LIGHT), (0.0, -1.0, 0.0))
    b.node("light", mesh=b.mesh("light", [(g, light)]))

    yfov = stable(2.0 * math.atan(0.5 * CORNELL_FILM / CORNELL_FOCAL))
    cam = b.camera("cornell_camera", yfov=yfov, aspect=1.0, znear=0.01, zfar=100.0)
    # glTF cameras look down local -Z; 180 degrees about +Y turns that into +Z (toward the box).
    b.node("camera", camera=cam, translation=[c * MM for c in CORNELL_CAMERA_POS],
           rotation=[0.0, 1.0, 0.0, 0.0])
    return b.glb("cornell_box")


# ---------------------------------------------------------------------------------------------
# Scene 2: conference room (8 m x 5 m x 3 m, long table, 18 chairs with thin legs)
# ---------------------------------------------------------------------------------------------
#
# Room: x in [-4, 4] (length), y in [0, 3] (up), z in [-2.5, 2.5] (width). The table runs along x.
# The camera stands near the +x end wall looking down the table toward -x.

ROOM_X = 4.0
ROOM_Y = 3.0
ROOM_Z = 2.5

TABLE_HALF_X = 2.8
TABLE_HALF_Z = 0.7
TABLE_TOP_Y = 0.76
TABLE_THICK = 0.04
TABLE_LEG = 0.07

SEAT_HALF_X = 0.23
SEAT_HALF_Z = 0.22
SEAT_TOP = 0.47
SEAT_THICK = 0.04
CHAIR_LEG = 0.025      # thin square legs
LEG_INSET = 0.01
BACK_TOP = 0.90
BACKREST_BOTTOM = 0.60

# Furniture group offset from the room centre (exercises parent/child transform composition).
FURNITURE_OFFSET = [-0.25, 0.0, 0.0]


def chair_geometry():
    """One chair in its own frame: origin on the floor under the seat centre, facing +Z (a sitter
    looks toward +Z), backrest on the -Z side. Returns (upholstery, metal) geometries."""
    fabric = Geometry()
    metal = Geometry()
    seat_bottom = SEAT_TOP - SEAT_THICK
    fabric.box((-SEAT_HALF_X, seat_bottom, -SEAT_HALF_Z), (SEAT_HALF_X, SEAT_TOP, SEAT_HALF_Z))
    h = 0.5 * CHAIR_LEG
    lx = SEAT_HALF_X - LEG_INSET - h
    lz = SEAT_HALF_Z - LEG_INSET - h
    for sx in (-1.0, 1.0):
        for sz in (-1.0, 1.0):
            cx, cz = sx * lx, sz * lz
            # Four thin legs from the floor to the seat (bottom and top faces are hidden).
            metal.box((cx - h, 0.0, cz - h), (cx + h, seat_bottom, cz + h), omit=("-y", "+y"))
    for sx in (-1.0, 1.0):
        cx, cz = sx * lx, -lz
        # Two uprights continuing the back legs above the seat, carrying the backrest.
        metal.box((cx - h, SEAT_TOP, cz - h), (cx + h, BACK_TOP, cz + h), omit=("-y",))
    fabric.box((-lx + h, BACKREST_BOTTOM, -lz - h), (lx - h, BACK_TOP - 0.02, -lz + h))
    return fabric, metal


def table_geometry():
    g = Geometry()
    g.box((-TABLE_HALF_X, TABLE_TOP_Y - TABLE_THICK, -TABLE_HALF_Z),
          (TABLE_HALF_X, TABLE_TOP_Y, TABLE_HALF_Z))
    h = 0.5 * TABLE_LEG
    for cx in (-TABLE_HALF_X + 0.25, 0.0, TABLE_HALF_X - 0.25):
        for cz in (-TABLE_HALF_Z + 0.15, TABLE_HALF_Z - 0.15):
            g.box((cx - h, 0.0, cz - h), (cx + h, TABLE_TOP_Y - TABLE_THICK, cz + h),
                  omit=("-y", "+y"))
    return g


def chair_placements():
    """(name, translation, yaw degrees) for every chair, in the furniture group's frame.

    Eight chairs along each long side, facing the table, plus one at each end. Small fixed yaw and
    distance offsets make the arrangement less regular (deterministic, no randomness)."""
    yaw_jitter = [4.0, -3.0, 2.0, -6.0, 3.0, -2.0, 5.0, -4.0]
    pull = [0.04, 0.10, 0.00, 0.07, 0.12, 0.02, 0.08, 0.05]
    spacing = 0.68
    out = []
    for side, (zsign, base_yaw) in enumerate(((-1.0, 0.0), (1.0, 180.0))):
        for i in range(8):
            x = (i - 3.5) * spacing
            k = (i + 3 * side) % 8
            z = zsign * (TABLE_HALF_Z + 0.28 + pull[k])
            name = "chair_%s_%d" % ("north" if zsign < 0 else "south", i + 1)
            out.append((name, [round(x, 6), 0.0, round(z, 6)], base_yaw + yaw_jitter[k]))
    # End chairs: the one at +x faces -x (yaw -90), the one at -x faces +x (yaw +90).
    out.append(("chair_east_end", [round(TABLE_HALF_X + 0.36, 6), 0.0, 0.0], -90.0 + 3.0))
    out.append(("chair_west_end", [round(-(TABLE_HALF_X + 0.32), 6), 0.0, 0.0], 90.0 - 4.0))
    return out


def build_conference():
    b = GltfBuilder()
    wall = b.material("wall_white", (0.66, 0.65, 0.62))
    accent = b.material("wall_accent_sage", (0.36, 0.55, 0.42))
    ceiling_m = b.material("ceiling", (0.70, 0.70, 0.70))
    floor_m = b.material("floor_warm", (0.45, 0.38, 0.30))
    wood = b.material("table_wood", (0.38, 0.26, 0.16))
    fabric_m = b.material("chair_fabric", (0.22, 0.34, 0.55))
    metal_m = b.material("chair_metal", (0.50, 0.50, 0.52))
    panel_m = b.material("light_panel", (0.80, 0.80, 0.80), emissive_rgb=(1.0, 0.93, 0.80),
                         emissive_strength=CONFERENCE_LIGHT_STRENGTH)

    X, Y, Z = ROOM_X, ROOM_Y, ROOM_Z
    centre = (0.0, 0.5 * Y, 0.0)

    def room_face(name, pts, mat):
        g = Geometry()
        g.polygon(pts, sub(centre, centroid(pts)))  # normals point into the room
        b.node(name, mesh=b.mesh(name, [(g, mat)]))

    room_face("floor", [(-X, 0, -Z), (X, 0, -Z), (X, 0, Z), (-X, 0, Z)], floor_m)
    room_face("ceiling", [(-X, Y, -Z), (X, Y, -Z), (X, Y, Z), (-X, Y, Z)], ceiling_m)
    room_face("wall_east", [(X, 0, -Z), (X, Y, -Z), (X, Y, Z), (X, 0, Z)], wall)
    room_face("wall_west", [(-X, 0, -Z), (-X, Y, -Z), (-X, Y, Z), (-X, 0, Z)], wall)
    room_face("wall_north", [(-X, 0, -Z), (X, 0, -Z), (X, Y, -Z), (-X, Y, -Z)], wall)
    room_face("wall_south_accent", [(-X, 0, Z), (X, 0, Z), (X, Y, Z), (-X, Y, Z)], accent)

    # Four emissive ceiling panels, 1.2 m x 0.6 m, 2 cm below the ceiling, facing down.
    panel_y = Y - 0.02
    hx, hz = 0.6, 0.3
    for i, (cx, cz) in enumerate(((-1.8, -1.2), (1.8, -1.2), (-1.8, 1.2), (1.8, 1.2))):
        g = Geometry()
        g.polygon([(cx - hx, panel_y, cz - hz), (cx + hx, panel_y, cz - hz),
                   (cx + hx, panel_y, cz + hz), (cx - hx, panel_y, cz + hz)], (0.0, -1.0, 0.0))
        name = "light_panel_%d" % (i + 1)
        b.node(name, mesh=b.mesh(name, [(g, panel_m)]))

    table_mesh = b.mesh("table", [(table_geometry(), wood)])
    fabric, metal = chair_geometry()
    chair_mesh = b.mesh("chair", [(fabric, fabric_m), (metal, metal_m)])

    children = [b.node("table", mesh=table_mesh, root=False)]
    for name, t, yaw in chair_placements():
        children.append(b.node(name, mesh=chair_mesh, translation=t, rotation=quat_yaw(yaw),
                               root=False))
    b.node("furniture", translation=FURNITURE_OFFSET, children=children)

    eye = (X - 0.35, 1.55, 0.85)
    target = (-2.6, 0.45, -0.25)
    cam = b.camera("conference_camera", yfov=stable(math.radians(55.0)), aspect=stable(4.0 / 3.0),
                   znear=0.01, zfar=100.0)
    b.node("camera", camera=cam, translation=list(eye), rotation=look_rotation(eye, target))
    return b.glb("conference_room")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    for name, build in (("cornell.glb", build_cornell), ("conference.glb", build_conference)):
        data = build()
        path = os.path.join(here, name)
        with open(path, "wb") as f:
            f.write(data)
        print("wrote %s (%d bytes)" % (os.path.relpath(path), len(data)))


if __name__ == "__main__":
    main()
