"""A scenario run: highway-env traffic, the PyBullet camera, ground truth, step by step.

Time: the traffic is integrated at ``sim.stepping.SIM_DT_S`` (100 Hz); the camera captures a frame
every ``camera.dt_s``; a controller decides once per frame. Frame k is captured at
t = k * camera.dt_s; its ground truth compares it with frame k-1.

What a run hands out is in ``sim.episode_records``, where its scripted actors start in
``sim.episode_placement`` and the footprint contact tests in ``sim.episode_contact``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from scenarios.spec import ScenarioCase, VruActorSpec
from sim import episode_contact
from sim.actor_truth import ActorTruth
from sim.camera import CameraConfig
from sim.episode_actors import Actor, actor_truths, obstruction_poses, vehicle_start, walker_for
from sim.episode_placement import overlap_offset_m
from sim.episode_records import Collision, Frame, StepTruth
from sim.episode_sensor import through_sensor
from sim.ground_truth import GroundTruth
from sim.stepping import capture_pose, captures_ground_truth, step_traffic, substeps
from sim.textures import TextureStyle
from sim.traffic import ActuatorConfig, EgoVehicle, ScriptedVehicle, TrafficVehicle, build_road
from sim.vehicles import EGO_SIZE_M, footprints_overlap, sample_spec
from sim.vru import vru_spec

__all__ = ["Collision", "Frame", "ScenarioSim", "StepTruth", "overlap_offset_m"]

STANDSTILL_MPS = 0.01  # [m/s]
POST_COLLISION_S = 1.0  # a run ends this long after the first contact [s] (Euro NCAP)
VIEW_MARGIN_M = 250.0  # road built this far beyond the furthest vehicle [m]


class ScenarioSim:
    """One run of a scenario case.

    Args:
        case: the resolved scenario.
        camera: camera config; rendering happens only when ``render`` is True.
        seed: draws scenery, vehicle appearance and background traffic.
        render: render camera frames and per-pixel ground truth.
        actuator: the ego's brake actuator.
        textures: the rendered world's ground and vehicle texture styles.
        sensor: ``sim.sensor.SensorEffects`` the rendered images go through (the
            controller's view of them), with the exact motion since the previous capture;
            None: clean renders. Depth, instances and every truth stay the renderer's.
    """

    def __init__(
        self,
        case: ScenarioCase,
        camera: CameraConfig,
        seed: int,
        render: bool,
        actuator: ActuatorConfig | None = None,
        textures: TextureStyle = TextureStyle(),
        sensor=None,
    ):
        self.case = case
        self.sensor = sensor
        if sensor is not None:
            from sim.sensor import REALISM_STREAM, new_codec

            self._sensor_rng = np.random.default_rng([seed, REALISM_STREAM])
            self._codecs = {view: new_codec(sensor) for view in ("wide", "fovea")}  # one stream per view
        self._last_capture: Frame | None = None
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
            if isinstance(a, VruActorSpec):
                spec = vru_spec(a.kind, rng, a.height_m)
                walker = walker_for(a, spec, v_ego, case.ego.conflict_s)
                placements.append((a, spec, walker))
                far_x = max(far_x, walker.pose_at(case.duration_s)[0])
                continue
            spec = sample_spec(rng, a.vehicle)
            x, y, heading = vehicle_start(a, spec, v_ego, case)
            placements.append((a, spec, x, y, heading))
            far_x = max(far_x, x + (a.speed_kph / 3.6 if a.direction == "same" else 0.0) * case.duration_s)
        far_x = max(far_x, v_ego * case.duration_s) + VIEW_MARGIN_M
        road = replace(case.road, x_end_m=far_x)
        self.road_cfg = road
        self.road = build_road(road, self.seed)
        self.path = case.path
        self.ego = EgoVehicle(self.road, 0.0, 0.0, v_ego, ego_len, ego_w, self.actuator, self.sim_dt_s, path=self.path)
        self.road.vehicles.append(self.ego)
        if self.render_enabled:
            from sim.world import World

            self.world = World(self.camera, road, seed=self.seed, style=self.textures)
        self.actors: list[Actor] = []
        for a, spec, *where in placements:
            if isinstance(a, VruActorSpec):
                self._add_vru(a, spec, where[0], v_ego)
                continue
            x, y, heading = where
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
                keep_lateral=a.direction in ("same", "oncoming"),  # crossing cars drive straight on
            )
            self._add_actor(spec, veh)
        self._add_background_traffic(v_ego)

    def _add_actor(self, spec, veh) -> None:
        self.road.vehicles.append(veh)
        instance = self.world.add_vehicle(spec) if self.world is not None else len(self.actors) + 1
        self.actors.append(Actor(instance, spec, veh, float(veh.speed)))

    def _add_vru(self, a: VruActorSpec, spec, walker, v_ego: float) -> None:
        """A road user (stepped beside the highway-env traffic), and the parked cars that hide it."""
        if self.world is not None:
            instance, part_ids = self.world.add_vru(spec)
        else:
            instance, part_ids = len(self.actors) + 1, []
        self.actors.append(Actor(instance, spec, walker, walker.v, part_ids))
        if a.obstruction:
            for i, (x, y, h) in enumerate(obstruction_poses(a, v_ego, self.case.ego.conflict_s, (4.5, 1.8))):
                car = sample_spec(self.rng, "van" if i == 0 else "car")
                self._add_actor(car, ScriptedVehicle(self.road, x, y, h, 0.0, car.length_m, car.width_m))

    def _add_background_traffic(self, v_ego: float) -> None:
        lanes = [k for k in range(-self.road_cfg.lanes_right, self.road_cfg.lanes_left + 1) if k != 0]
        for i in range(self.case.traffic if lanes else 0):
            spec = sample_spec(self.rng, str(self.rng.choice(["car", "car", "van", "truck"])))
            lane = lanes[i % len(lanes)]
            x = float(self.rng.uniform(-30.0, 150.0))
            speed = max(0.0, v_ego + float(self.rng.uniform(-8.0, 8.0)))
            veh = TrafficVehicle(self.road, x, self.road_cfg.lane_center_y_m(lane), speed, spec.length_m, spec.width_m)
            corners = episode_contact.vehicle_corners
            if any(footprints_overlap(corners(veh, spec), corners(o.vehicle, o.spec)) for o in self.actors):
                continue
            self._add_actor(spec, veh)

    # ------------------------------------------------------------------ state
    def actor_truths(self) -> list[ActorTruth]:
        """Every actor's exact truth now (``sim.episode_actors.actor_truths``)."""
        return actor_truths(self)

    def truth(self) -> StepTruth:
        actors = self.actor_truths()
        threats = [a for a in actors if a.in_path and a.ahead]
        critical = min(threats, key=lambda a: (a.ttc_s, a.gap_m)) if threats else None
        return StepTruth(self.t_s, float(self.ego.speed), actors, critical, collision=self.collision)

    def min_distance_m(self, below_m: float = math.inf) -> float:
        """Smallest footprint distance [m] from the ego to any actor; actors whose
        bounding circles are already further than ``below_m`` are skipped."""
        return episode_contact.min_distance_m(self.ego, self.actors, below_m)

    # ------------------------------------------------------------------ camera
    def _camera_pose(self) -> np.ndarray:
        return capture_pose(self.camera, self.rng, self.ego.world_pose())

    def capture(self) -> Frame:
        """Render the current state (poses mirrored into PyBullet first)."""
        cam_T_world = self._camera_pose()
        poses = {a.instance: a.vehicle.world_pose() for a in self.actors}
        if self.world is None:
            return Frame(self.t_s, None, cam_T_world, poses)
        part_T: dict[int, np.ndarray] = {}
        for a in self.actors:
            if a.is_vru:
                part_T.update(self.world.pose_vru(a.instance, a.spec, poses[a.instance], a.vehicle.travelled_m))
            else:
                self.world.set_vehicle_pose(a.instance, *poses[a.instance])
        r = self.world.render(cam_T_world)
        fovea = self.camera.fovea()
        f = self.world.render(cam_T_world, pinhole=fovea) if fovea is not None else None
        frame = Frame(self.t_s, r.rgb, cam_T_world, poses, r.depth_m, r.instance, f, r.part, part_T)
        if self.sensor is not None:
            frame = self._through_sensor(frame)
        return frame

    def _through_sensor(self, frame: Frame) -> Frame:
        """Each view's image through ``self.sensor`` (``sim.episode_sensor``)."""
        prev, self._last_capture = self._last_capture, frame
        return through_sensor(self, frame, prev)

    def ground_truth(self, prev: Frame, latest: Frame, view: str = "wide") -> GroundTruth:
        """Exact per-pixel ground truth of ``latest`` against ``prev`` in view 'wide' or 'fovea'."""
        _, depth_m, instance = latest.view(view)
        return captures_ground_truth(self.camera.view(view), depth_m, instance, latest.parts(view), latest, prev)

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
            vehicles = [a.vehicle for a in self.actors if not a.is_vru]
            step_traffic(self.road, self.ego, vehicles, decel_mps2, self.t_s, dt)
            for a in self.actors:
                if a.is_vru:
                    a.vehicle.step(dt)
        self.t_s = round(self.t_s + dt, 9)
        self.ego_braked |= self.ego.current_accel_mps2 < -0.5
        if self.collision is None:
            d = self.min_distance_m(below_m=self.min_gap_m)
            if d == 0.0:
                self._check_collision()
            self.min_gap_m = min(self.min_gap_m, d)

    def _check_collision(self) -> None:
        a = episode_contact.touching_actor(self.ego, self.actors)
        if a is not None:
            heading = -self.ego.heading
            along = np.array([math.cos(heading), math.sin(heading)])
            v_rel = float(self.ego.speed) - float(a.vehicle.world_velocity() @ along)
            self.collision = Collision(self.t_s, a.instance, float(self.ego.speed), v_rel)
            for v in [*self.road.vehicles, *(a.vehicle for a in self.actors if a.is_vru)]:
                v.speed = 0.0  # all come to rest at the contact (highway-env does too)

    def done(self, truth: StepTruth) -> str | None:
        """Why the run ends now, or None: ``collision`` (1 s after it), ``standstill``,
        ``resolved`` (the ego braked and nothing closes in), ``passed`` (every actor wholly
        behind the ego and not gaining: the outcome is settled), ``duration``."""
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
        if episode_contact.all_passed(self.ego, self.actors):
            return "passed"
        if self.t_s >= self.case.duration_s - 1e-9:
            return "duration"
        return None

    def _actor(self, instance: int) -> Actor:
        return next(a for a in self.actors if a.instance == instance)

    def close(self) -> None:
        if self.world is not None:
            self.world.close()
            self.world = None
