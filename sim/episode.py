"""A scenario run: highway-env traffic, the PyBullet camera, ground truth, step by step.

Time: the traffic is integrated at ``sim.stepping.SIM_DT_S`` (100 Hz); the camera captures a frame
every ``camera.dt_s``; a controller decides once per frame. Frame k is captured at
t = k * camera.dt_s; its ground truth compares it with frame k-1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from scenarios.spec import ActorSpec, ScenarioCase
from sim.actor_truth import ActorTruth, actor_truth, footprint_distance
from sim.camera import CameraConfig
from sim.ground_truth import GroundTruth
from sim.stepping import capture_pose, pair_ground_truth, step_traffic, substeps
from sim.textures import TextureStyle
from sim.traffic import ActuatorConfig, EgoVehicle, ScriptedVehicle, TrafficVehicle, build_road
from sim.vehicles import EGO_SIZE_M, VehicleSpec, footprint_corners, footprints_overlap, sample_spec

if TYPE_CHECKING:  # the world imports PyBullet, which a run without a camera never needs
    from sim.world import Render

STANDSTILL_MPS = 0.01  # [m/s]
POST_COLLISION_S = 1.0  # a run ends this long after the first contact [s] (Euro NCAP)
VIEW_MARGIN_M = 250.0  # road built this far beyond the furthest vehicle [m]


def overlap_offset_m(overlap_pct: float, target_width_m: float, ego_width_m: float = EGO_SIZE_M[1]) -> float:
    """Lateral offset [m] of the target's centreline from the ego's (+ = left) for an
    overlap of ``overlap_pct``.

    Euro NCAP: the overlap is the share of the ego's (VUT's) width that overlaps the
    target, whatever the target's width; O < 0 puts the target on the ego's right. At
    +-50 % the target's near edge lies on the ego's centreline. At 100 % (or whenever the
    target is too narrow to cover the requested share) the centrelines are aligned.
    """
    shared_m = abs(overlap_pct) / 100.0 * ego_width_m
    if shared_m >= min(ego_width_m, target_width_m):
        return 0.0
    # the target's near edge lies ``shared_m`` inside the ego's far side
    return math.copysign((ego_width_m + target_width_m) / 2 - shared_m, overlap_pct)


@dataclass(frozen=True)
class Collision:
    t_s: float
    instance: int
    impact_speed_mps: float  # ego speed at first contact [m/s]
    relative_impact_speed_mps: float  # ego minus actor speed along the ego's heading [m/s]


@dataclass
class StepTruth:
    """Ground truth at a frame. Never part of what a (non-oracle) policy observes."""

    t_s: float
    ego_speed_mps: float
    actors: list[ActorTruth]
    critical: ActorTruth | None  # in-path actor ahead with the smallest TTC
    gt: GroundTruth | None = None  # per-pixel maps (only when the camera renders)
    collision: Collision | None = None


@dataclass
class _Actor:
    instance: int
    spec: VehicleSpec
    vehicle: ScriptedVehicle | TrafficVehicle
    initial_speed_mps: float


@dataclass
class Frame:
    """A captured frame: the wide view's image (H, W, 3) uint8, exact depth and instances,
    the fovea's render (``sim.world.Render``, same pose) when the camera has one, and the
    poses (world x [m], y [m], heading [rad]) of every actor at capture time."""

    t_s: float
    image: np.ndarray | None
    cam_T_world: np.ndarray
    poses: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    depth_m: np.ndarray | None = None
    instance: np.ndarray | None = None
    fovea: Render | None = None

    def view(self, name: str) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]:
        """(image, depth_m, instance) of view 'wide' or 'fovea' (Nones where not rendered)."""
        if name == "wide":
            return self.image, self.depth_m, self.instance
        if self.fovea is None:
            return None, None, None
        return self.fovea.rgb, self.fovea.depth_m, self.fovea.instance


class ScenarioSim:
    """One run of a scenario case.

    Args:
        case: the resolved scenario.
        camera: camera config; rendering happens only when ``render`` is True.
        seed: draws scenery, vehicle appearance and background traffic.
        render: render camera frames and per-pixel ground truth.
        actuator: the ego's brake actuator.
        textures: the rendered world's ground and vehicle texture styles.
    """

    def __init__(
        self,
        case: ScenarioCase,
        camera: CameraConfig,
        seed: int,
        render: bool,
        actuator: ActuatorConfig | None = None,
        textures: TextureStyle = TextureStyle(),
    ):
        self.case = case
        self.camera = camera
        self.textures = textures
        self.seed = seed
        self.render_enabled = render
        self.actuator = actuator or ActuatorConfig()
        self.rng = np.random.default_rng(seed)
        self.n_sub, self.sim_dt_s = substeps(camera.dt_s)
        self.world = None
        self._build()

    # ------------------------------------------------------------------ setup
    def _build(self) -> None:
        case, rng = self.case, self.rng
        v_ego = case.ego.speed_kph / 3.6
        ego_len, ego_w, _ = EGO_SIZE_M
        placements = []
        far_x = 0.0
        for a in case.actors:
            spec = sample_spec(rng, a.vehicle)
            x, y, heading = self._placement(a, spec, v_ego)
            placements.append((a, spec, x, y, heading))
            far_x = max(far_x, x + (a.speed_kph / 3.6 if a.direction == "same" else 0.0) * case.duration_s)
        far_x = max(far_x, v_ego * case.duration_s) + VIEW_MARGIN_M
        road = replace(case.road, x_end_m=far_x)
        self.road_cfg = road
        self.road = build_road(road, self.seed)
        self.ego = EgoVehicle(self.road, 0.0, 0.0, v_ego, ego_len, ego_w, self.actuator, self.sim_dt_s)
        self.road.vehicles.append(self.ego)
        if self.render_enabled:
            from sim.world import World

            self.world = World(self.camera, road, seed=self.seed, style=self.textures)
        self.actors: list[_Actor] = []
        for a, spec, x, y, heading in placements:
            lc = None
            if a.lane_change is not None:
                lc = (a.lane_change.start_s, a.lane_change.duration_s, road.lane_center_y_m(a.lane_change.to_lane))
            veh = ScriptedVehicle(
                self.road,
                x,
                y,
                heading,
                a.speed_kph / 3.6,
                spec.length_m,
                spec.width_m,
                accel_mps2=-a.decel_mps2 if a.decel_mps2 > 0 else a.accel_mps2,
                brake_onset_s=a.brake_onset_s if a.decel_mps2 > 0 else 0.0,
                lane_change=lc,
            )
            self._add_actor(spec, veh)
        self._add_background_traffic(v_ego)

    def _placement(self, a: ActorSpec, spec: VehicleSpec, v_ego: float) -> tuple[float, float, float]:
        """Initial (x, y, heading) of a scripted actor from Euro NCAP-style parameters."""
        gap = a.headway_m if a.headway_m is not None else a.headway_s * v_ego
        x = EGO_SIZE_M[0] / 2 + gap + spec.length_m / 2
        y = self.case.road.lane_center_y_m(a.lane) + overlap_offset_m(a.overlap_pct, spec.width_m)
        heading = 0.0 if a.direction == "same" else math.pi
        return x, y, heading

    def _add_actor(self, spec: VehicleSpec, veh) -> None:
        self.road.vehicles.append(veh)
        instance = self.world.add_vehicle(spec) if self.world is not None else len(self.actors) + 1
        self.actors.append(_Actor(instance, spec, veh, float(veh.speed)))

    def _add_background_traffic(self, v_ego: float) -> None:
        lanes = [k for k in range(-self.road_cfg.lanes_right, self.road_cfg.lanes_left + 1) if k != 0]
        for i in range(self.case.traffic if lanes else 0):
            spec = sample_spec(self.rng, str(self.rng.choice(["car", "car", "van", "truck"])))
            lane = lanes[i % len(lanes)]
            x = float(self.rng.uniform(-30.0, 150.0))
            speed = max(0.0, v_ego + float(self.rng.uniform(-8.0, 8.0)))
            veh = TrafficVehicle(self.road, x, self.road_cfg.lane_center_y_m(lane), speed, spec.length_m, spec.width_m)
            if any(footprints_overlap(self._corners(veh, spec), self._corners(o.vehicle, o.spec)) for o in self.actors):
                continue
            self._add_actor(spec, veh)

    # ------------------------------------------------------------------ state
    @staticmethod
    def _corners(veh, spec: VehicleSpec) -> np.ndarray:
        x, y, h = veh.world_pose()
        return footprint_corners(x, y, h, spec.length_m, spec.width_m)

    def _ego_corners(self) -> np.ndarray:
        x, y, h = self.ego.world_pose()
        return footprint_corners(x, y, h, EGO_SIZE_M[0], EGO_SIZE_M[1])

    def actor_truths(self) -> list[ActorTruth]:
        ego_pose = self.ego.world_pose()
        return [
            actor_truth(
                a.instance,
                ego_pose,
                EGO_SIZE_M[:2],
                float(self.ego.speed),
                a.vehicle.world_pose(),
                (a.spec.length_m, a.spec.width_m),
                a.vehicle.world_velocity(),
            )
            for a in self.actors
        ]

    def truth(self) -> StepTruth:
        actors = self.actor_truths()
        threats = [a for a in actors if a.in_path and a.ahead]
        critical = min(threats, key=lambda a: (a.ttc_s, a.gap_m)) if threats else None
        return StepTruth(self.t_s, float(self.ego.speed), actors, critical, collision=self.collision)

    def min_distance_m(self, below_m: float = math.inf) -> float:
        """Smallest footprint distance [m] from the ego to any actor; actors whose
        bounding circles are already further than ``below_m`` are skipped."""
        ex, ey, _ = self.ego.world_pose()
        ego_r = 0.5 * math.hypot(EGO_SIZE_M[0], EGO_SIZE_M[1])
        ego = None
        best = math.inf
        for a in self.actors:
            ax, ay, _ = a.vehicle.world_pose()
            lower = math.hypot(ax - ex, ay - ey) - ego_r - 0.5 * math.hypot(a.spec.length_m, a.spec.width_m)
            if lower >= min(best, below_m):
                continue
            ego = self._ego_corners() if ego is None else ego
            best = min(best, footprint_distance(ego, self._corners(a.vehicle, a.spec)))
        return best

    # ------------------------------------------------------------------ camera
    def _camera_pose(self) -> np.ndarray:
        return capture_pose(self.camera, self.rng, self.ego.world_pose())

    def capture(self) -> Frame:
        """Render the current state (poses mirrored into PyBullet first)."""
        cam_T_world = self._camera_pose()
        poses = {a.instance: a.vehicle.world_pose() for a in self.actors}
        if self.world is None:
            return Frame(self.t_s, None, cam_T_world, poses)
        for inst, pose in poses.items():
            self.world.set_vehicle_pose(inst, *pose)
        r = self.world.render(cam_T_world)
        fovea = self.camera.fovea()
        f = self.world.render(cam_T_world, pinhole=fovea) if fovea is not None else None
        return Frame(self.t_s, r.rgb, cam_T_world, poses, r.depth_m, r.instance, f)

    def ground_truth(self, prev: Frame, latest: Frame, view: str = "wide") -> GroundTruth:
        """Exact per-pixel ground truth of ``latest`` against ``prev`` in view 'wide' or 'fovea'."""
        _, depth_m, instance = latest.view(view)
        return pair_ground_truth(
            self.camera.view(view),
            depth_m,
            instance,
            latest.cam_T_world,
            prev.cam_T_world,
            latest.poses,
            prev.poses,
            latest.t_s - prev.t_s,
        )

    # ------------------------------------------------------------------ stepping
    def reset(self) -> StepTruth:
        self.t_s = 0.0
        self.collision: Collision | None = None
        self.min_gap_m = self.min_distance_m()
        self.ego_braked = False
        return self.truth()

    def substep(self, decel_mps2: float) -> None:
        """Integrate one traffic step with a requested ego deceleration [m/s^2]."""
        dt = self.sim_dt_s
        if self.collision is None:
            step_traffic(self.road, self.ego, [a.vehicle for a in self.actors], decel_mps2, self.t_s, dt)
        self.t_s = round(self.t_s + dt, 9)
        self.ego_braked |= self.ego.current_accel_mps2 < -0.5
        if self.collision is None:
            d = self.min_distance_m(below_m=self.min_gap_m)
            if d == 0.0:
                self._check_collision()
            self.min_gap_m = min(self.min_gap_m, d)

    def _check_collision(self) -> None:
        ego = self._ego_corners()
        for a in self.actors:
            if footprints_overlap(ego, self._corners(a.vehicle, a.spec)):
                heading = -self.ego.heading
                along = np.array([math.cos(heading), math.sin(heading)])
                v_rel = float(self.ego.speed) - float(a.vehicle.world_velocity() @ along)
                self.collision = Collision(self.t_s, a.instance, float(self.ego.speed), v_rel)
                for v in self.road.vehicles:  # both come to rest at the contact (highway-env does too)
                    v.speed = 0.0
                return

    def done(self, truth: StepTruth) -> str | None:
        """Why the run ends now, or None."""
        if self.collision is not None:
            return "collision" if self.t_s >= self.collision.t_s + POST_COLLISION_S - 1e-9 else None
        still_closing = truth.critical is not None and truth.critical.closing_speed_mps > 1e-6
        if self.case.ego.speed_kph > 0 and self.ego.speed < STANDSTILL_MPS and not still_closing:
            return "standstill"
        if (
            self.ego_braked
            and truth.critical is None
            or (
                self.ego_braked
                and truth.critical.closing_speed_mps < 0
                and self._actor(truth.critical.instance).vehicle.current_accel_mps2 >= 0
            )
        ):
            return "resolved"
        if self.t_s >= self.case.duration_s - 1e-9:
            return "duration"
        return None

    def _actor(self, instance: int) -> _Actor:
        return next(a for a in self.actors if a.instance == instance)

    def close(self) -> None:
        if self.world is not None:
            self.world.close()
            self.world = None
