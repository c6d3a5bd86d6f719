"""The PyBullet world: owns one DIRECT client, the scenery, the vehicle bodies, the camera.

Several worlds can live in one process: nothing here touches PyBullet's implicit
global client. Rendering uses TinyRenderer, whose depth buffer is exact float depth.

Cost: a world is cheap to rebuild in place (``reset``): the client and the textures it
has loaded are kept, only the bodies are replaced. Static scenery goes in as compound
bodies of up to ``MAX_SHAPES_PER_BODY`` shapes sharing one material, because PyBullet
pays a fixed cost per body created (the render cost is rasterisation and barely
depends on the body count).

Convention: world frame z up, x along the road, y left (see :mod:`sim.camera`).
Instance ids: -1 = nothing (sky), 0 = static scenery, 1..N = actors (vehicles and road
users) in the order they were added. Part ids (``Render.part``) name the rigid body a
pixel lies on: a vehicle's part id is its instance id; each rigid part of a road user
(:mod:`sim.vru`) has its own id from ``PART_ID_BASE`` on, so that its motion can differ
from its trunk's.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from pathlib import Path

import numpy as np

from sim.quiet import c_output_suppressed

with c_output_suppressed():
    import pybullet as p
    from pybullet_utils import bullet_client

from sim import textures
from sim.bodies import create_part_body, create_static_bodies, create_vehicle_bodies, quat_from_matrix
from sim.camera import CameraConfig, Pinhole
from sim.scenery import RoadConfig, Scenery, StaticShape, build_scenery
from sim.vehicles import VehicleSpec
from sim.vru import VruSpec, part_poses, parts
from sim.world_render import Render, render_view  # noqa: F401  (Render re-exported)

PART_ID_BASE = 1 << 20  # part ids of road users' rigid parts start here (instances stay below)
SCENES_PER_CLIENT = 256  # reconnect after this many resets: removeBody keeps the visual shape records


def _quat_z(heading_rad: float) -> list[float]:
    return [0.0, 0.0, math.sin(heading_rad / 2), math.cos(heading_rad / 2)]


class World:
    """A PyBullet scene with a straight road, roadside structure and vehicles.

    Args:
        camera: the ego camera's image format and mounting.
        road: the road layout.
        seed: draws the scenery, textures and lighting.
        light_direction: direction *towards* the light in the world frame; drawn from
            ``seed`` when None.
        bank: procedural textures to use; a private bank seeded with ``seed`` when None.
        style: the texture styles of that private bank (ignored with ``bank``).
    """

    def __init__(
        self,
        camera: CameraConfig,
        road: RoadConfig,
        seed: int,
        light_direction: tuple[float, float, float] | None = None,
        bank: textures.TextureBank | None = None,
        style: textures.TextureStyle = textures.TextureStyle(),
    ):
        self._client: bullet_client.BulletClient | None = None
        self._tmp = Path(tempfile.mkdtemp(prefix="bittc_world_"))
        self.bank = bank if bank is not None else textures.TextureBank(seed, self._tmp, style.ground, style.vehicles)
        self._sky: dict[tuple[int, int], np.ndarray] = {}  # render (height, width) -> sky image
        self._scenes_on_client = 0
        self.reset(camera, road, seed, light_direction)

    def _connect(self) -> None:
        if self._client is not None:
            self._client.disconnect()
        with c_output_suppressed():
            self._client = bullet_client.BulletClient(connection_mode=p.DIRECT)
        self._texture_ids: dict[tuple[str, int, int], int] = {}
        self._bodies: list[int] = []
        self._scenes_on_client = 0

    def reset(
        self,
        camera: CameraConfig,
        road: RoadConfig,
        seed: int,
        light_direction: tuple[float, float, float] | None = None,
    ) -> None:
        """Replace the scene: new camera, road, scenery and lighting, no vehicles.

        The result renders exactly as a new ``World(camera, road, seed, light_direction,
        bank)`` would; only the client and its loaded textures are reused.
        """
        if self._client is None or self._scenes_on_client >= SCENES_PER_CLIENT:
            self._connect()
        else:
            for uid in self._bodies:
                self._client.removeBody(uid)
            self._bodies.clear()
        self._scenes_on_client += 1
        self.camera = camera
        self.road = road
        self.rng = np.random.default_rng(seed)
        self._instance_of_uid: dict[int, int] = {}  # PyBullet body uid -> instance id
        self._vehicle_uid: dict[int, int] = {}  # instance id -> body uid
        self._wheel_uid: dict[int, int] = {}  # instance id -> body uid of its wheels
        self._vehicle_pose: dict[int, tuple[float, float, float]] = {}
        self._vehicle_base_z: dict[int, float] = {}  # lower-body centre height [m]
        self._part_of_uid: dict[int, int] = {}  # body uid of a road user's part -> part id
        self._vru_parts: dict[int, list[tuple[int, int]]] = {}  # instance -> [(part id, uid)]
        if light_direction is None:
            az = self.rng.uniform(0, 2 * math.pi)
            el = self.rng.uniform(math.radians(25), math.radians(70))
            light_direction = (math.cos(az) * math.cos(el), math.sin(az) * math.cos(el), math.sin(el))
        self.light_direction = tuple(float(v) for v in light_direction)
        self.add_scenery(build_scenery(road, self.rng))

    # ------------------------------------------------------------------ lifecycle
    @property
    def client(self) -> bullet_client.BulletClient:
        if self._client is None:
            raise RuntimeError("this World is closed")
        return self._client

    def close(self) -> None:
        if self._client is not None:
            self._client.disconnect()
            self._client = None
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:  # pragma: no cover - best effort
        try:
            self.close()
        except Exception:
            pass

    # ------------------------------------------------------------------ building
    def texture(self, kind: str, variant: int, palette_index: int = 0) -> int:
        """PyBullet texture id of a bank texture (loaded once per world)."""
        key = (kind, int(variant) % textures.VARIANTS, int(palette_index))
        if key not in self._texture_ids:
            self._texture_ids[key] = self.client.loadTexture(str(self.bank.path(kind, key[1], key[2])))
        return self._texture_ids[key]

    def _register(self, uid: int, instance: int) -> None:
        if uid < 0:
            raise RuntimeError("PyBullet failed to create a body")
        self._instance_of_uid[uid] = instance
        self._bodies.append(uid)

    def add_static_shapes(self, shapes: list[StaticShape], texture_id: int | None, rgb=(1.0, 1.0, 1.0)) -> list[int]:
        """Add static shapes of one material; returns the body uids.

        Boxes go in compound bodies of up to ``MAX_SHAPES_PER_BODY``; spheres are baked
        into one low-polygon mesh per ``SPHERES_PER_MESH`` (see :mod:`sim.meshes`).
        """
        uids = create_static_bodies(self.client, shapes, rgb)
        for uid in uids:
            if texture_id is not None:
                self.client.changeVisualShape(uid, -1, textureUniqueId=texture_id)
            self._register(uid, 0)
        return uids

    def add_scenery(self, scenery: Scenery) -> None:
        """Add the static bodies of ``scenery``: its textures loaded in the order listed, then
        one ``add_static_shapes`` per material."""
        ids = {ref: self.texture(ref.kind, ref.variant) for ref in scenery.textures}
        for g in scenery.groups:
            self.add_static_shapes(g.shapes, None if g.texture is None else ids[g.texture], g.rgb)

    def add_static_box(self, center_m, half_extents_m, texture_id: int | None, rgb=(1.0, 1.0, 1.0)) -> int:
        """One static box (``half_extents_m`` [m]); returns its body uid."""
        return self.add_static_shapes([StaticShape.box(center_m, half_extents_m)], texture_id, rgb)[0]

    def add_vehicle(self, spec: VehicleSpec) -> int:
        """Add a vehicle (hidden below ground until posed); returns its instance id.

        Two bodies: the boxes (lower body at its own centre, the rest as fixed links) and
        the four wheels as one low-polygon mesh in the footprint frame (see
        :mod:`sim.meshes`); ``set_vehicle_pose`` moves both.
        """
        c = self.client
        variant = int(self.rng.integers(textures.VARIANTS))
        dressed = self.bank.vehicle_style(variant) == "dressed"
        kinds = ("paint", "glass", *(textures.FITTING_KINDS if dressed else ()))
        tex = {k: self.texture(k, variant, spec.palette_index) for k in kinds}
        uid, wheel_uid, base_z = create_vehicle_bodies(c, spec, tex, dressed)
        instance = self._next_instance()
        self._vehicle_uid[instance] = uid
        self._wheel_uid[instance] = wheel_uid
        self._vehicle_base_z[instance] = base_z
        self._register(uid, instance)
        self._register(wheel_uid, instance)
        return instance

    def _next_instance(self) -> int:
        return len(self._vehicle_uid) + len(self._vru_parts) + 1

    def add_vru(self, spec: VruSpec) -> tuple[int, list[int]]:
        """Add a pedestrian or cyclist (hidden until posed) -> (instance id, part id of each
        part of ``sim.vru.parts(spec)``, in order); ``set_part_poses`` moves the parts."""
        instance = self._next_instance()
        self._vru_parts[instance] = []
        for part in parts(spec):
            uid = create_part_body(self.client, part)
            part_id = PART_ID_BASE + len(self._part_of_uid)
            self._register(uid, instance)
            self._part_of_uid[uid] = part_id
            self._vru_parts[instance].append((part_id, uid))
        return instance, [pid for pid, _ in self._vru_parts[instance]]

    # ------------------------------------------------------------------ state
    def set_part_poses(self, instance: int, world_T_parts: list[np.ndarray]) -> None:
        """Place each part of road user ``instance`` at its world_T_part (4x4, ``sim.vru.part_poses``)."""
        entries = self._vru_parts[instance]
        if len(world_T_parts) != len(entries):
            raise ValueError(f"road user {instance} has {len(entries)} parts, got {len(world_T_parts)} poses")
        for (_, uid), T in zip(entries, world_T_parts):
            q = quat_from_matrix(np.asarray(T)[:3, :3])
            self.client.resetBasePositionAndOrientation(uid, [float(v) for v in T[:3, 3]], q)

    def pose_vru(self, instance: int, spec: VruSpec, pose, travelled_m: float) -> dict[int, np.ndarray]:
        """Place road user ``instance`` of ``spec`` at planar ``pose`` (x, y, heading) having
        travelled ``travelled_m`` [m] (its gait phase, its wheels' angle); -> part id ->
        world_T_part (4x4, ``sim.vru.part_poses``), what its ground truth moves with."""
        Ts = part_poses(spec, pose, travelled_m)
        self.set_part_poses(instance, Ts)
        return {pid: T for (pid, _), T in zip(self._vru_parts[instance], Ts)}

    def set_vehicle_pose(self, instance: int, x_m: float, y_m: float, heading_rad: float) -> None:
        """Place a vehicle: footprint centre (x, y) on the ground, heading about z [rad]."""
        uid = self._vehicle_uid[instance]
        z = self._vehicle_base_z[instance]
        self.client.resetBasePositionAndOrientation(uid, [x_m, y_m, z], _quat_z(heading_rad))
        self.client.resetBasePositionAndOrientation(self._wheel_uid[instance], [x_m, y_m, 0.0], _quat_z(heading_rad))
        self._vehicle_pose[instance] = (float(x_m), float(y_m), float(heading_rad))

    @property
    def part_lut(self) -> np.ndarray | None:
        """int32 array: body uid -> part id (its instance for every body but a road user's
        parts; -1 for uids of no body); None when the world holds no road user."""
        if not self._part_of_uid:
            return None
        lut = self.instance_lut
        for uid, pid in self._part_of_uid.items():
            lut[uid] = pid
        return lut

    @property
    def instance_lut(self) -> np.ndarray:
        """int32 array: PyBullet body uid -> instance id (-1 for uids of no body)."""
        lut = np.full(max(self._instance_of_uid, default=-1) + 1, -1, np.int32)
        for uid, inst in self._instance_of_uid.items():
            lut[uid] = inst
        return lut

    # ------------------------------------------------------------------ rendering
    def render(self, cam_T_world: np.ndarray, with_rgb: bool = True, pinhole: Pinhole | None = None) -> Render:
        """Render the scene from an OpenCV camera pose ``cam_T_world`` (4x4) through
        ``pinhole`` (default: the camera's wide view; ``camera.fovea()`` for the fovea,
        which shares the pose); with ``with_rgb=False`` the render's ``rgb`` is None (depth
        and instances only). See ``sim.world_render``."""
        return render_view(self, cam_T_world, with_rgb, pinhole)
