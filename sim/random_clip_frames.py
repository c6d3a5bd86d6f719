"""The frames of a random clip and its metadata: the traffic stepped between captures, each
frame rendered through one view, and the JSON description of the clip (meta.json)."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from sim.camera import Pinhole
from sim.random_scene_draw import SceneDraw
from sim.stepping import capture_pose, step_traffic
from sim.world import World


def render_frames(
    rng, world: World, hw_road, ego, actors, scene: SceneDraw, clip_length, n_sub, sim_dt, view: Pinhole, vrus=()
):
    """-> (images, (render, cam_T_world, poses, part poses) per frame, the per-frame state records),
    seen through ``view``; ``vrus``: road users (``sim.random_vrus.place_vrus``), stepped beside
    the traffic, each part posed (part id -> world_T_part)."""
    images, frames, states = [], [], []
    t = 0.0
    for k in range(clip_length):
        if k > 0:
            for _ in range(n_sub):
                step_traffic(hw_road, ego, [veh for _, _, veh, _ in actors], scene.ego_decel, t, sim_dt)
                for v in vrus:
                    v[2].step(sim_dt)
                t += sim_dt
        poses = {inst: veh.world_pose() for inst, _, veh, _ in actors}
        for inst, pose in poses.items():
            world.set_vehicle_pose(inst, *pose)
        part_T = {}
        for inst, spec, walker, _, gait_m in vrus:
            poses[inst] = walker.world_pose()
            part_T.update(world.pose_vru(inst, spec, poses[inst], walker.travelled_m + gait_m))
        ex, ey, eh = ego.world_pose()
        cam_T_world = capture_pose(scene.camera, rng, (ex, ey, eh))
        r = world.render(cam_T_world, pinhole=view)
        images.append(r.rgb)
        frames.append((r, cam_T_world, poses, part_T))
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
                    for inst, _, veh, _ in [*actors, *(v[:4] for v in vrus)]
                ],
            }
        )
    return images, frames, states


def clip_meta(sample_seed: int, scene: SceneDraw, view: Pinhole, actors, states, vrus=()) -> dict:
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
        ]
        + [
            {"instance": inst, "kind": spec.kind, "class": spec.cls, "height_m": spec.height_m, "motion": motion}
            for inst, spec, _, motion, _ in vrus
        ],
        "frames": states,
    }
