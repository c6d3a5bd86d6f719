"""Closed-loop run of one scenario case with one controller; writes its outputs.

The loop itself is ``sim.loop.ClosedLoop`` (latency, frame skipping, command queue,
end of run). The first warning / brake are logged at the traffic step in which they
take effect, with the exact bumper-to-bumper TTC of the critical actor at that step.
Per-pixel TTC (the estimator's, the fence lag's) is to the camera plane instead.
The summary is built in ``sim.run_summary``, the files in ``sim.run_files`` and the
video frames in ``sim.run_video``.
"""

from __future__ import annotations

import time
from pathlib import Path

from controllers.base import Controller
from scenarios.spec import ScenarioCase
from sim.camera import CameraConfig
from sim.episode import ScenarioSim
from sim.fence_lag import FenceLagMeter
from sim.latency import LatencyMode, parse_latency
from sim.loop import ClosedLoop
from sim.run_files import trace_rows, write_outputs
from sim.run_summary import LAG_KEYS, SUMMARY_KEYS, TABLE_CAMERA_KEYS, summarize
from sim.run_video import video_frame
from sim.textures import TextureStyle
from sim.traffic import ActuatorConfig
from sim.video import VideoWriter

__all__ = ["LAG_KEYS", "SUMMARY_KEYS", "TABLE_CAMERA_KEYS", "default_latency", "lag_meter_for", "run_case", "summarize"]


def run_case(
    case: ScenarioCase,
    controller: Controller,
    camera: CameraConfig,
    seed: int,
    out_dir: Path | None = None,
    video: bool = False,
    actuator: ActuatorConfig | None = None,
    textures: TextureStyle = TextureStyle(),
    latency: LatencyMode | None = None,
    export_kitti: Path | None = None,
    sensor=None,
) -> dict:
    """Run ``case`` closed loop; returns the summary. With ``out_dir`` writes
    summary.json, trace.csv, config.yaml, timing.json (and camera.mp4 with ``video``).

    ``latency`` defaults to ``measured`` for controllers that need the camera and
    ``fixed:0`` for the others. With a fixed or profile latency, summary.json,
    trace.csv and config.yaml are the same bytes for the same seed; wall-clock figures
    go to timing.json. ``export_kitti``: also write the run's frames in the KITTI raw layout
    into that folder (``sim.kitti_export``). ``sensor``: ``sim.sensor.SensorEffects`` the
    camera's images go through (``ScenarioSim``)."""
    wall0 = time.perf_counter()
    latency = latency or default_latency(controller)
    render = controller.needs_camera or video or export_kitti is not None
    sim = ScenarioSim(case, camera, seed, render=render, actuator=actuator, textures=textures, sensor=sensor)
    writer = VideoWriter(out_dir / "camera.mp4", camera.fps_hz) if (video and out_dir is not None) else None
    lag = lag_meter_for(controller)
    exporter = None
    if export_kitti is not None:
        from sim.kitti_export import KittiExporter

        exporter = KittiExporter(sim, export_kitti)
    hook = _capture_hook(writer, exporter, camera, lambda: loop)
    loop = ClosedLoop(
        sim,
        latency,
        num_alphas=controller.num_alphas,
        pairs=controller.needs_camera,
        frame_stride=controller.frame_stride,
        on_capture=hook,
        lag_meter=lag,
    )
    try:
        loop.drive(controller)
        summary = summarize(case, controller, seed, loop, latency, lag)
        if out_dir is not None:
            timing = {
                "wall_time_s": round(time.perf_counter() - wall0, 3),
                **{k: round(v, 4) for k, v in sorted(loop.timing.items())},
            }
            write_outputs(
                out_dir,
                case,
                controller,
                camera,
                seed,
                sim.actuator,
                summary,
                trace_rows(loop),
                video,
                textures,
                latency,
                timing,
                sensor,
            )
            if writer is not None:
                writer.close()
        if exporter is not None:
            exporter.finish()
        return summary
    except BaseException:
        if writer is not None:
            writer.abort()
        if exporter is not None:
            exporter.abort()
        raise
    finally:
        sim.close()


def _capture_hook(writer, exporter, camera: CameraConfig, loop_of):
    """The loop's capture hook: the video frame (``writer``) and the KITTI export, or None."""
    hooks = []
    if writer is not None:
        scale = writer.scale_for(camera.width_px)
        hooks.append(lambda rec, frame: writer.write(video_frame(frame, rec, loop_of(), scale)))
    if exporter is not None:
        hooks.append(exporter)
    return (lambda rec, frame: [h(rec, frame) for h in hooks]) if hooks else None


def lag_meter_for(controller: Controller) -> FenceLagMeter | None:
    """A fence-lag meter counting inside as the controller does (its ``prob_inside``), for camera controllers."""
    if not controller.needs_camera:
        return None
    return FenceLagMeter(getattr(getattr(controller, "cfg", None), "prob_inside", 0.5))


def default_latency(controller: Controller) -> LatencyMode:
    """``measured`` for controllers that look at the camera, ``fixed:0`` otherwise."""
    return parse_latency("measured" if controller.needs_camera else "fixed:0")
