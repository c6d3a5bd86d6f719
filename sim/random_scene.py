"""Randomised scenes for training data: a road, an ego, 0-12 actors, a short clip.

Everything is drawn from one numpy Generator seeded by the sample's seed, so a
(dataset seed, sample seed) pair fixes every byte of the clip, whichever process
renders it. Ground truth follows :mod:`sim.ground_truth` (maps in the latest frame's
grid, tau from the latest frame's capture time).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from sim.camera import CameraConfig, Pinhole
from sim.fovea_scene import (
    FOVEA_CLASSES,
    FOVEA_EGO_SPEED_MPS,
    FOVEA_MAX_OTHERS,
    fovea_camera,
    fovea_other,
    fovea_target,
    threat_motion,
)
from sim.ground_truth import GroundTruth
from sim.scenery import RoadConfig
from sim.stepping import capture_pose, pair_ground_truth, step_traffic, substeps
from sim.textures import TextureBank
from sim.traffic import ActuatorConfig, EgoVehicle, ScriptedVehicle, build_road
from sim.vehicles import EGO_SIZE_M, footprint_corners, footprints_overlap, sample_spec
from sim.world import World

MOTIONS = ("approaching", "receding", "oncoming", "crossing", "lateral", "stationary", "braking", "following")
TTC_RANGE_S = (0.5, 20.0)  # closing actors are placed at a TTC drawn log-uniformly from this range [s]
X_RANGE_M = (6.0, 120.0)  # distance ahead of the ego [m]
CLASSES = ("car", "car", "car", "gvt", "van", "truck")
MAX_ACTORS = 12
EGO_MAX_SPEED_MPS = 130 / 3.6  # [m/s]
# braking cases ahead (``ahead_share``): what a collision-warning camera must fence on time
AHEAD_MOTIONS = ("stationary", "slower", "braking")
AHEAD_CLASSES = ("gvt", "car", "van", "truck")
AHEAD_TTC_RANGE_S = (0.3, 4.0)  # [s] bumper-to-bumper TTC at the first frame, log-uniform
AHEAD_OVERLAP = (0.25, 1.0)  # |share of the ego's width overlapped|, either side (Euro NCAP: 50-100 %)
AHEAD_EGO_SPEED_MPS = (10 / 3.6, EGO_MAX_SPEED_MPS)  # [m/s]
AHEAD_MAX_OTHER_ACTORS = 6


@dataclass
class Clip:
    """K frames and the ground truth of each consecutive pair.

    images: K arrays (H, W, 3) uint8, oldest first. gts[j] compares frame j+1 (latest)
    with frame j (previous). meta: JSON-serialisable description (intrinsics, dt,
    camera, ego and actor states per frame, scene parameters).
    """

    images: list[np.ndarray]
    gts: list[GroundTruth]
    meta: dict


def random_camera(rng: np.random.Generator, base: CameraConfig) -> CameraConfig:
    """Jitter the mounting: height, pitch, vertical FOV and per-frame rotation noise."""
    return replace(
        base,
        mount_height_m=float(rng.uniform(1.1, 1.8)),
        pitch_deg=float(rng.uniform(-1.0, 5.0)),
        vfov_deg=float(rng.uniform(24.0, 40.0)),
        jitter_deg=float(rng.uniform(0.0, 0.4)),
    )


def random_road(rng: np.random.Generator) -> RoadConfig:
    return RoadConfig(
        lanes_left=int(rng.integers(0, 4)),
        lanes_right=int(rng.integers(0, 3)),
        lane_width_m=float(rng.uniform(3.0, 3.8)),
        x_start_m=-20.0,
        x_end_m=160.0,
        markings_max_x_m=90.0,
        roadside_spacing_m=float(rng.uniform(12.0, 35.0)),
        barrier=bool(rng.random() < 0.6),
        buildings=bool(rng.random() < 0.8),
    )


def _actor_motion(rng: np.random.Generator, motion: str, road: RoadConfig, v_ego: float):
    """(x, y, heading, speed, accel, keep_lateral) for one actor."""
    lanes = list(range(-road.lanes_right, road.lanes_left + 1))
    lane_y = road.lane_center_y_m(int(rng.choice(lanes))) + float(rng.uniform(-0.4, 0.4))
    x = float(rng.uniform(*X_RANGE_M))
    heading, accel, keep = 0.0, 0.0, True
    if motion == "approaching":
        speed = max(0.0, v_ego - float(rng.uniform(1.0, 20.0)))
    elif motion == "receding":
        speed = v_ego + float(rng.uniform(1.0, 15.0))
    elif motion == "oncoming":
        heading, speed = math.pi, float(rng.uniform(3.0, 30.0))
    elif motion == "crossing":
        side = float(rng.choice([-1.0, 1.0]))
        heading = side * math.pi / 2 + float(rng.normal(0.0, 0.15))
        lane_y = -side * float(rng.uniform(0.0, road.y_left_edge_m + 8.0))
        x, speed, keep = float(rng.uniform(8.0, 60.0)), float(rng.uniform(1.0, 12.0)), False
    elif motion == "lateral":
        heading = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.3))
        speed, keep = max(0.0, v_ego + float(rng.uniform(-8.0, 8.0))), False
    elif motion == "stationary":
        speed = 0.0
    elif motion == "following":  # moves exactly like the ego: eta = 1, tau = inf
        speed = v_ego
    else:  # braking
        speed, accel = max(0.0, v_ego + float(rng.uniform(-5.0, 5.0))), -float(rng.uniform(2.0, 8.0))
    closing = v_ego - speed * math.cos(heading)
    if motion != "crossing" and closing < -0.5:  # opening gap: keep it near enough to cover pixels
        x = float(rng.uniform(X_RANGE_M[0], 50.0))
    if motion != "crossing" and closing > 0.5:
        # spread TTCs evenly on a log scale instead of letting near, fast actors dominate
        ttc = math.exp(rng.uniform(math.log(TTC_RANGE_S[0]), math.log(TTC_RANGE_S[1])))
        x = float(np.clip(ttc * closing, *X_RANGE_M))
    return x, lane_y, heading, speed, accel, keep


def _ahead_actor(rng: np.random.Generator, v_ego: float, length_m: float, width_m: float):
    """(x, y, heading, speed, accel, motion) of a braking case ahead of the ego in its lane.

    Overlap O (share of the ego's width overlapped, Euro NCAP's definition for equal
    widths): the target's centre sits (1 - |O|) (w_ego + w_target) / 2 to the left
    (O > 0) or right (O < 0) of the ego's."""
    motion = str(rng.choice(AHEAD_MOTIONS))
    speed, accel = threat_motion(rng, motion, v_ego)
    ttc = math.exp(rng.uniform(math.log(AHEAD_TTC_RANGE_S[0]), math.log(AHEAD_TTC_RANGE_S[1])))
    gap = float(np.clip(ttc * max(v_ego - speed, 0.5), 2.0, X_RANGE_M[1]))
    overlap = float(rng.uniform(*AHEAD_OVERLAP)) * float(rng.choice([-1.0, 1.0]))
    y = math.copysign(1.0, overlap) * (1.0 - abs(overlap)) * (EGO_SIZE_M[1] + width_m) / 2
    return EGO_SIZE_M[0] / 2 + gap + length_m / 2, y, 0.0, speed, accel, f"ahead-{motion}"


def render_clip(
    sample_seed: int,
    base_camera: CameraConfig,
    clip_length: int,
    bank: TextureBank,
    world: World | None = None,
    ahead_share: float = 0.0,
    fovea_share: float = 0.0,
) -> Clip:
    """Draw a scene from ``sample_seed`` and render ``clip_length`` frames of it.

    ``world``: a world built on ``bank`` to rebuild in place (``World.reset``) instead of
    building and closing a new one; the clip's bytes are the same either way.
    ``ahead_share``: the probability that the scene also has a braking case ahead
    (``_ahead_actor``; the ego then drives at 10-130 km/h, with at most
    ``AHEAD_MAX_OTHER_ACTORS`` random actors). At 0 nothing more is drawn, so the bytes
    are those of the datasets made before the option.
    ``fovea_share``: the probability that the scene is seen through a fovea instead
    (:mod:`sim.fovea_scene`: a far target in or near the ego's lane and look-alikes; the
    images, ground truth and intrinsics are the fovea's). At 0 nothing more is drawn.

    Steps, each drawing from the one ``rng`` in this order: the scene (camera, road, ego),
    the world, the actors, the frames; then the ground truth and the metadata.
    """
    if world is not None and world.bank is not bank:
        raise ValueError("render_clip: the world must use the given texture bank")
    rng = np.random.default_rng(sample_seed)
    scene = _draw_scene(rng, base_camera, ahead_share, fovea_share)
    hw_road = build_road(scene.road, seed=sample_seed % (2**31))
    n_sub, sim_dt = substeps(scene.camera.dt_s)
    ego = EgoVehicle(hw_road, 0.0, 0.0, scene.v_ego, EGO_SIZE_M[0], EGO_SIZE_M[1], ActuatorConfig(delay_s=0.0), sim_dt)
    hw_road.vehicles.append(ego)
    world_seed = int(rng.integers(2**31))
    owned = world is None
    if owned:
        world = World(scene.camera, scene.road, seed=world_seed, bank=bank)
    else:
        world.reset(scene.camera, scene.road, seed=world_seed)
    try:
        actors = _place_actors(rng, world, hw_road, scene)
        view = scene.camera.fovea() if scene.fovea else scene.camera.wide()
        images, frames, states = _render_frames(
            rng, world, hw_road, ego, actors, scene, clip_length, n_sub, sim_dt, view
        )
        gts = [
            pair_ground_truth(view, r1.depth_m, r1.instance, c1, c0, p1, p0, scene.camera.dt_s)
            for (_, c0, p0), (r1, c1, p1) in zip(frames[:-1], frames[1:])
        ]
    finally:
        if owned:
            world.close()
    return Clip(images, gts, _clip_meta(sample_seed, scene, view, actors, states))


@dataclass(frozen=True)
class _Scene:
    camera: CameraConfig
    road: RoadConfig
    v_ego: float  # [m/s]
    ego_decel: float  # [m/s^2]
    ahead: bool  # a braking case ahead
    fovea: bool = False  # seen through the camera's fovea (sim.fovea_scene)


def _draw_scene(rng: np.random.Generator, base_camera: CameraConfig, ahead_share: float, fovea_share: float) -> _Scene:
    camera = random_camera(rng, base_camera)
    road = random_road(rng)
    v_ego = 0.0 if rng.random() < 0.08 else float(rng.uniform(0.0, EGO_MAX_SPEED_MPS))
    ego_decel = float(rng.uniform(2.0, 7.0)) if rng.random() < 0.1 else 0.0
    ahead = ahead_share > 0 and rng.random() < ahead_share
    if ahead:
        v_ego = float(rng.uniform(*AHEAD_EGO_SPEED_MPS))
    fovea = fovea_share > 0 and rng.random() < fovea_share  # drawn only when asked: old datasets keep their bytes
    if fovea:
        camera, ahead = fovea_camera(rng, camera), False
        v_ego = float(rng.uniform(*FOVEA_EGO_SPEED_MPS))
    return _Scene(camera, road, v_ego, ego_decel, ahead, fovea)


def _place_actors(rng, world: World, hw_road, scene: _Scene) -> list:
    """-> [(instance, spec, vehicle, motion)]: the braking case ahead (if drawn), then random
    actors placed clear of the ego and of each other (5 tries each)."""
    actors = []
    taken = [footprint_corners(0.0, 0.0, 0.0, EGO_SIZE_M[0] + 2.0, EGO_SIZE_M[1] + 1.0)]
    if scene.ahead or scene.fovea:
        spec = sample_spec(rng, str(rng.choice(FOVEA_CLASSES if scene.fovea else AHEAD_CLASSES)))
        draw = fovea_target if scene.fovea else _ahead_actor
        x, y, heading, speed, accel, motion = draw(rng, scene.v_ego, spec.length_m, spec.width_m)
        taken.append(footprint_corners(x, y, heading, spec.length_m + 1.0, spec.width_m + 0.5))
        veh = ScriptedVehicle(hw_road, x, y, heading, speed, spec.length_m, spec.width_m, accel_mps2=accel)
        hw_road.vehicles.append(veh)
        actors.append((world.add_vehicle(spec), spec, veh, motion))
    if scene.fovea:
        _place_fovea_others(rng, world, hw_road, scene, taken, actors)
        return actors
    for _ in range(int(rng.integers(0, (AHEAD_MAX_OTHER_ACTORS if scene.ahead else MAX_ACTORS) + 1))):
        motion = str(rng.choice(MOTIONS))
        spec = sample_spec(rng, str(rng.choice(CLASSES)))
        _place_clear(
            world, hw_road, taken, actors, spec, lambda m=motion: (*_actor_motion(rng, m, scene.road, scene.v_ego), m)
        )
    return actors


def _place_clear(world: World, hw_road, taken: list, actors: list, spec, draw) -> None:
    """Place a vehicle of ``spec`` where ``draw()`` -> (x, y, heading, speed, accel, keep_lateral,
    motion) puts it clear of every footprint in ``taken`` (5 tries; none fits: not placed),
    appending its footprint to ``taken`` and (instance, spec, vehicle, motion) to ``actors``."""
    for _attempt in range(5):
        x, y, heading, speed, accel, keep, motion = draw()
        corners = footprint_corners(x, y, heading, spec.length_m + 1.0, spec.width_m + 0.5)
        if not any(footprints_overlap(corners, t) for t in taken):
            break
    else:
        return
    taken.append(corners)
    veh = ScriptedVehicle(
        hw_road, x, y, heading, speed, spec.length_m, spec.width_m, accel_mps2=accel, keep_lateral=keep
    )
    hw_road.vehicles.append(veh)
    actors.append((world.add_vehicle(spec), spec, veh, motion))


def _place_fovea_others(rng, world: World, hw_road, scene: _Scene, taken: list, actors: list) -> None:
    """Append 0-``FOVEA_MAX_OTHERS`` vehicles a fovea sees beside its target (adjacent,
    oncoming, another lead), each clear of the others (5 tries each)."""
    for _ in range(int(rng.integers(0, FOVEA_MAX_OTHERS + 1))):
        spec = sample_spec(rng, str(rng.choice(CLASSES)))

        def draw(spec=spec):
            x, y, heading, speed, motion = fovea_other(rng, scene.road, scene.v_ego, spec.length_m)
            return x, y, heading, speed, 0.0, True, motion

        _place_clear(world, hw_road, taken, actors, spec, draw)


def _render_frames(rng, world: World, hw_road, ego, actors, scene: _Scene, clip_length, n_sub, sim_dt, view: Pinhole):
    """-> (images, (render, cam_T_world, poses) per frame, the per-frame state records), seen through ``view``."""
    images, frames, states = [], [], []
    t = 0.0
    for k in range(clip_length):
        if k > 0:
            for _ in range(n_sub):
                step_traffic(hw_road, ego, [veh for _, _, veh, _ in actors], scene.ego_decel, t, sim_dt)
                t += sim_dt
        poses = {inst: veh.world_pose() for inst, _, veh, _ in actors}
        for inst, pose in poses.items():
            world.set_vehicle_pose(inst, *pose)
        ex, ey, eh = ego.world_pose()
        cam_T_world = capture_pose(scene.camera, rng, (ex, ey, eh))
        r = world.render(cam_T_world, pinhole=view)
        images.append(r.rgb)
        frames.append((r, cam_T_world, poses))
        states.append(
            {
                "t_s": round(t, 6),
                "cam_T_world": np.round(cam_T_world, 12).tolist(),
                "ego": {"x_m": ex, "y_m": ey, "heading_rad": eh, "speed_mps": float(ego.speed)},
                "actors": [
                    {
                        "instance": inst,
                        "x_m": poses[inst][0],
                        "y_m": poses[inst][1],
                        "heading_rad": poses[inst][2],
                        "speed_mps": float(veh.speed),
                    }
                    for inst, _, veh, _ in actors
                ],
            }
        )
    return images, frames, states


def _clip_meta(sample_seed: int, scene: _Scene, view: Pinhole, actors, states) -> dict:
    camera = scene.camera
    fx, fy, cx, cy = view.intrinsics()
    cam = asdict(camera)
    extra = {}
    if cam["fovea_zoom"] is None or cam["fovea_width_share"] == 1:  # a full-width view
        del cam["fovea_width_share"]  # (the bytes of the earlier datasets)
    if cam["fovea_zoom"] is None:  # wide-view scenes: their bytes stay those of the earlier datasets
        del cam["fovea_zoom"]
    else:  # seen through the fovea: the intrinsics above are the fovea's
        extra["view"] = {"name": "fovea", "zoom": camera.fovea_zoom}
    return {
        "sample_seed": int(sample_seed),
        **extra,
        "intrinsics": {"fx_px": float(fx), "fy_px": float(fy), "cx_px": float(cx), "cy_px": float(cy)},
        "dt_s": camera.dt_s,
        "camera": cam,
        "road": asdict(scene.road),
        "ego_decel_mps2": scene.ego_decel,
        "actors": [
            {
                "instance": inst,
                "kind": spec.kind,
                "length_m": spec.length_m,
                "width_m": spec.width_m,
                "height_m": spec.height_m,
                "palette_index": spec.palette_index,
                "motion": motion,
            }
            for inst, spec, _, motion in actors
        ],
        "frames": states,
    }
