"""PyBullet bodies of the world's shapes, made on a given client (``sim.world.World`` owns
the client and registers the bodies' instances).

Convention: world frame z up, x along the road, y left; a vehicle's bodies are built in
its footprint frame and hidden 50 m below the ground until posed.
"""

from __future__ import annotations

import math

import numpy as np

from sim import meshes
from sim.quiet import c_output_suppressed
from sim.scenery import StaticShape
from sim.vehicles import VehicleSpec, parts

with c_output_suppressed():
    import pybullet as p

MAX_SHAPES_PER_BODY = 16  # PyBullet renders at most this many shapes of one createVisualShapeArray
WHEEL_LENGTH_PER_HALF_WIDTH = 4.0  # mesh wheel length / the wheel part's half width
SPHERES_PER_MESH = 32  # spheres baked into one mesh body


def create_static_bodies(c, shapes: list[StaticShape], rgb=(1.0, 1.0, 1.0)) -> list[int]:
    """Static bodies of ``shapes`` (one material) on client ``c``; returns their uids.

    Boxes go in compound bodies of up to ``MAX_SHAPES_PER_BODY``; spheres are baked into
    one low-polygon mesh per ``SPHERES_PER_MESH`` (see :mod:`sim.meshes`).
    """
    uids = []
    boxes = [s for s in shapes if s.kind == "box"]
    spheres = [s for s in shapes if s.kind == "sphere"]
    if len(boxes) + len(spheres) != len(shapes):
        raise ValueError(f"unknown static shape kinds {sorted({s.kind for s in shapes} - {'box', 'sphere'})}")
    for i in range(0, len(boxes), MAX_SHAPES_PER_BODY):
        chunk = boxes[i : i + MAX_SHAPES_PER_BODY]
        vs = c.createVisualShapeArray(
            shapeTypes=[p.GEOM_BOX] * len(chunk),
            halfExtents=[list(s.size_m) for s in chunk],
            visualFramePositions=[list(s.center_m) for s in chunk],
            rgbaColors=[[*rgb, 1.0]] * len(chunk),
        )
        uids.append(c.createMultiBody(0, -1, vs))
    for i in range(0, len(spheres), SPHERES_PER_MESH):
        chunk = spheres[i : i + SPHERES_PER_MESH]
        mesh = meshes.merge(meshes.SPHERE, [[s.size_m[0]] * 3 for s in chunk], [s.center_m for s in chunk])
        vs = c.createVisualShape(p.GEOM_MESH, rgbaColor=[*rgb, 1.0], **mesh)
        uids.append(c.createMultiBody(0, -1, vs))
    return uids


def create_vehicle_bodies(c, spec: VehicleSpec, tex: dict[str, int], dressed: bool = False) -> tuple[int, int, float]:
    """The two bodies of a vehicle on client ``c``: the boxes (lower body at its own centre,
    the rest as fixed links, textured from ``tex`` by part; ``dressed``: with plates and
    lamps) and the four wheels as one mesh in the footprint frame. Returns (body uid, wheel
    uid, the body's base height [m])."""
    all_parts = parts(spec, dressed)
    boxes = [part for part in all_parts if part.shape == "box"]
    wheels = [part for part in all_parts if part.shape == "wheel"]
    shapes = [c.createVisualShape(p.GEOM_BOX, halfExtents=list(part.half_extents_m)) for part in boxes]
    n = len(shapes) - 1
    base_pos = np.asarray(boxes[0].center_m)
    uid = c.createMultiBody(
        0,
        -1,
        shapes[0],
        basePosition=[0, 0, -50.0],
        baseInertialFramePosition=[0, 0, 0],
        linkMasses=[0] * n,
        linkCollisionShapeIndices=[-1] * n,
        linkVisualShapeIndices=shapes[1:],
        linkPositions=[list(np.asarray(part.center_m) - base_pos) for part in boxes[1:]],
        linkOrientations=[[0, 0, 0, 1]] * n,
        linkInertialFramePositions=[[0, 0, 0]] * n,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * n,
        linkParentIndices=[0] * n,
        linkJointTypes=[p.JOINT_FIXED] * n,
        linkJointAxis=[[0, 0, 1]] * n,
    )
    for link, part in enumerate(boxes):
        c.changeVisualShape(uid, link - 1, textureUniqueId=tex[part.texture])
    # wheel half extents are (radius, half width, radius); the unit wheel is 1 m long
    # and twice the part's width, so that it shows beside the body as PyBullet's own
    # cylinders of that length did
    mesh = meshes.merge(
        meshes.WHEEL,
        [[w.half_extents_m[0], WHEEL_LENGTH_PER_HALF_WIDTH * w.half_extents_m[1], w.half_extents_m[0]] for w in wheels],
        [w.center_m for w in wheels],
    )
    wheel_uid = c.createMultiBody(
        0,
        -1,
        c.createVisualShape(p.GEOM_MESH, rgbaColor=[0.08, 0.08, 0.08, 1.0], **mesh),
        basePosition=[0, 0, -50.0],
    )
    return uid, wheel_uid, float(base_pos[2])


def create_part_body(c, part) -> int:
    """One rigid part of a road user (``sim.vru.VruPart``) on client ``c``, its frame at the
    part's pivot, hidden 50 m below the ground until posed; returns its uid. Boxes keep their
    own colours; a wheel is a dark cylinder about the part's y axis."""
    if part.wheel_radius_m > 0:
        r = part.wheel_radius_m
        mesh = meshes.merge(meshes.WHEEL, [[r, part.wheel_width_m, r]], [[0.0, 0.0, 0.0]])
        vs = c.createVisualShape(p.GEOM_MESH, rgbaColor=[0.08, 0.08, 0.08, 1.0], **mesh)
    else:
        if not 0 < len(part.boxes) <= MAX_SHAPES_PER_BODY:
            raise ValueError(f"part {part.name!r} has {len(part.boxes)} boxes: need 1..{MAX_SHAPES_PER_BODY}")
        vs = c.createVisualShapeArray(
            shapeTypes=[p.GEOM_BOX] * len(part.boxes),
            halfExtents=[list(b.half_m) for b in part.boxes],
            visualFramePositions=[list(b.center_m) for b in part.boxes],
            rgbaColors=[[*b.rgb, 1.0] for b in part.boxes],
        )
    return c.createMultiBody(0, -1, vs, basePosition=[0, 0, -50.0])


def quat_from_matrix(R: np.ndarray) -> list[float]:
    """(x, y, z, w) quaternion of a rotation matrix (Shepperd's method, stable for any angle)."""
    tr = float(np.trace(R))
    i = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
    if i == 0:
        w = math.sqrt(1.0 + tr) / 2
        return [(R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w), w]
    a, b, c = (i - 1, i % 3, (i + 1) % 3)
    q = [0.0, 0.0, 0.0, 0.0]
    q[a] = math.sqrt(max(1.0 + R[a, a] - R[b, b] - R[c, c], 0.0)) / 2
    q[b] = (R[b, a] + R[a, b]) / (4 * q[a])
    q[c] = (R[c, a] + R[a, c]) / (4 * q[a])
    q[3] = (R[c, b] - R[b, c]) / (4 * q[a])
    return q
