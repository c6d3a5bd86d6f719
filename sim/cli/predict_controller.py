"""The geofence controller open loop on footage (``bittc predict CLIP --controller geofence``):
its calibration from the footage's, and one job per paired frame with the ego's motion of
that frame (``--ego-speed`` or ``--oxts``), its stage and its fences written to the frame's
CSV row."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.footage_views import fence_columns


def open_loop_controller(args, est, thr, views, cams, stride, rate_ratio):
    """The geofence controller of ``bittc predict CLIP --controller geofence``: the views' calibrations
    from the footage's, its persistence and release scaled by ``rate_ratio`` (jobs per 10 Hz job)
    -> (controller, calibration)."""
    from controllers.base import Calibration
    from controllers.geofence import GeofenceConfig, GeofenceController
    from sim.camera import CameraConfig
    from sim.vehicles import EGO_SIZE_M

    def cal(view, fovea=None):
        c, (h, w) = cams[view], views[view][1]
        return Calibration(
            w, h, c.fx_px, c.fy_px, c.cx_px, c.cy_px, args.camera_height, CameraConfig().mount_forward_m,
            args.pitch, est.dt_s, float(EGO_SIZE_M[0]), float(EGO_SIZE_M[1]), fovea,
        )  # fmt: skip

    base = GeofenceConfig(thresholds_s=tuple(thr), frame_stride=stride)
    cfg = replace(
        base,
        persistence_frames=base.persistence_frames * rate_ratio,
        release_frames=base.release_frames * rate_ratio,
    )
    ctrl = GeofenceController(est, cfg)
    calibration = cal("wide", cal("fovea") if "fovea" in views else None)
    ctrl.reset(calibration)
    return ctrl, calibration


def controller_step(run, row: dict, now: dict, before: dict, t_s: float, i: int):
    """One job of the controller on the pair ending at frame ``i`` -> (pictures, HUD lines,
    alert); fills ``row``."""
    from controllers.base import Observation
    from sim.video import geofence_overlay

    a = run.args
    speed, yaw = (float(run.motion[0][i]), float(run.motion[1][i])) if run.motion else (float(a.ego_speed), 0.0)
    turn = None  # the pair's rotation [rad]: the yaw rates from its earlier frame on, by the trapezoid rule
    if run.motion:
        j, times = int(run.partner[i]), run.clip.times_s
        turn = float(np.trapezoid(np.asarray(run.motion[1][j : i + 1], float), np.asarray(times[j : i + 1], float)))
    obs = Observation(
        t_s, speed, now["wide"], before["wide"], run.pair_dt_s, run.calibration,
        now.get("fovea"), before.get("fovea"), ego_yaw_rate_radps=yaw, pair_yaw_rad=turn,
    )  # fmt: skip
    row |= {"ego_speed_mps": round(speed, 4), "ego_yaw_rate_radps": round(yaw, 5)}
    cmd = run.ctrl.act(obs, None)
    tel = cmd.telemetry
    pictures = []
    for v, gv in cmd.views().items():
        fence_columns(row, v, gv.thresholds_s, gv.maps, run.rois[v], a.roi is not None)
        pictures.append(geofence_overlay(now[v], gv))
    row |= {
        "stage": tel["stage"],
        "warning": int(cmd.warning),
        "decel_mps2": round(float(cmd.decel_mps2), 3),
        "fence_fired_s": tel["fence_fired_s"],
        "fired_view": tel["fired_view"],
    }
    if cmd.warning and run.first["warning"] is None:
        run.first["warning"] = row["t_s"]
    if cmd.decel_mps2 > 0 and run.first["brake"] is None:
        run.first["brake"] = row["t_s"]
    return pictures, [f"t {t_s:.2f} s  {tel['stage']}  {cmd.decel_mps2:.1f} m/s2"], bool(cmd.warning)
