"""Low-polygon meshes for TinyRenderer, merged into one mesh per body.

PyBullet's own spheres and cylinders are finely tessellated: ~0.5 ms each to create and
many triangles to draw. Here a unit shape is scaled and placed many times in one mesh,
which is created in one call (``createVisualShape(GEOM_MESH, vertices=..., indices=...,
uvs=..., normals=...)``). Place such a mesh with its body's base pose only: TinyRenderer
does not rotate a vertex-mesh *link* with its body.

Units: unit shapes have radius 1 (the cylinder: length 1 along y, centred at the
origin); ``merge`` scales them per axis [m] and offsets them [m] in the body frame.
"""

from __future__ import annotations

import math

import numpy as np

SPHERE_RINGS = 6  # latitude bands
SPHERE_SEGMENTS = 10  # longitude segments
CYLINDER_SEGMENTS = 12


class UnitMesh:
    """vertices (V, 3), normals (V, 3), uvs (V, 2) float64; indices (3T,) int."""

    def __init__(self, vertices, indices, uvs, normals) -> None:
        self.vertices = np.asarray(vertices, np.float64)
        self.indices = np.asarray(indices, np.int64)
        self.uvs = np.asarray(uvs, np.float64)
        self.normals = np.asarray(normals, np.float64)
        self._tiled: dict[int, tuple[list, list, list]] = {}

    def tiled(self, n: int) -> tuple[list, list, list]:
        """(indices, uvs, unit normals) of ``n`` copies as lists; cached, they do not
        depend on where the copies go (list conversion is most of a merge's cost)."""
        if n not in self._tiled:
            idx = (self.indices[None] + len(self.vertices) * np.arange(n)[:, None]).reshape(-1)
            self._tiled[n] = (idx.tolist(), self.uvs.tolist() * n, self.normals.tolist() * n)
        return self._tiled[n]


def uv_sphere(rings: int = SPHERE_RINGS, segments: int = SPHERE_SEGMENTS) -> UnitMesh:
    """Unit sphere: (rings + 1) x (segments + 1) vertices, the seam duplicated for the uvs."""
    verts, uvs = [], []
    for i in range(rings + 1):
        theta = math.pi * i / rings  # from the north pole
        for j in range(segments + 1):
            phi = 2 * math.pi * j / segments
            verts.append([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
            uvs.append([j / segments, i / rings])
    idx = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return UnitMesh(verts, idx, uvs, verts)


def cylinder_y(segments: int = CYLINDER_SEGMENTS) -> UnitMesh:
    """Unit cylinder with its axis along y (a wheel's axle): side quads and two-sided caps."""
    verts, uvs, normals, idx = [], [], [], []
    for j in range(segments + 1):
        phi = 2 * math.pi * j / segments
        c, s = math.cos(phi), math.sin(phi)
        for y in (-0.5, 0.5):
            verts.append([c, y, s])
            uvs.append([j / segments, y + 0.5])
            normals.append([c, 0.0, s])
    for j in range(segments):
        a = 2 * j
        idx += [a, a + 2, a + 1, a + 1, a + 2, a + 3]
    for y in (-0.5, 0.5):
        centre = len(verts)
        verts.append([0.0, y, 0.0])
        uvs.append([0.5, 0.5])
        normals.append([0.0, math.copysign(1.0, y), 0.0])
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            verts.append([math.cos(phi), y, math.sin(phi)])
            uvs.append([0.5 + 0.5 * math.cos(phi), 0.5 + 0.5 * math.sin(phi)])
            normals.append([0.0, math.copysign(1.0, y), 0.0])
        for j in range(segments):  # both windings: TinyRenderer culls back faces of meshes
            a, b = centre + 1 + j, centre + 1 + (j + 1) % segments
            idx += [centre, a, b, centre, b, a]
    return UnitMesh(verts, idx, uvs, normals)


def merge(unit: UnitMesh, scales_m, offsets_m) -> dict:
    """Copies of ``unit`` scaled per axis and offset [m], as createVisualShape keyword args."""
    scales = np.asarray(scales_m, np.float64).reshape(-1, 3)
    offsets = np.asarray(offsets_m, np.float64).reshape(-1, 3)
    verts = (unit.vertices[None] * scales[:, None] + offsets[:, None]).reshape(-1, 3)
    indices, uvs, normals = unit.tiled(len(scales))
    if not np.all(scales == scales[:, :1]):  # normals of a surface scaled unevenly
        scaled = unit.normals[None] / scales[:, None]
        scaled /= np.maximum(np.linalg.norm(scaled, axis=-1, keepdims=True), 1e-12)
        normals = scaled.reshape(-1, 3).tolist()
    return {"vertices": verts.tolist(), "indices": indices, "uvs": uvs, "normals": normals}


SPHERE = uv_sphere()
WHEEL = cylinder_y()
