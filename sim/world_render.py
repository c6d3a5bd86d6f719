"""Rendering a ``sim.world.World`` through one pinhole view: colour (optionally
supersampled), exact depth, instance and part ids per pixel (conventions: ``sim.world``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim import textures
from sim.camera import Pinhole, view_matrix_gl
from sim.quiet import c_output_suppressed

with c_output_suppressed():
    import pybullet as p


@dataclass
class Render:
    """One rendered frame at the camera's output resolution.

    rgb: (H, W, 3) uint8. depth_m: (H, W) float32, depth Z along the optical axis [m]
    (``far_m`` where nothing was hit). instance: (H, W) int32 (-1 sky, 0 static, >0 actor).
    part: (H, W) int32, the rigid part (see ``sim.world``); None where no road user
    was rendered (then every part is its instance).
    """

    rgb: np.ndarray
    depth_m: np.ndarray
    instance: np.ndarray
    part: np.ndarray | None = None


def render_view(world, cam_T_world: np.ndarray, with_rgb: bool = True, pinhole: Pinhole | None = None) -> Render:
    """Render the scene from an OpenCV camera pose ``cam_T_world`` (4x4) through
    ``pinhole`` (default: the camera's wide view; ``camera.fovea()`` for the fovea,
    which shares the pose); with ``with_rgb=False`` the render's ``rgb`` is None (depth
    and instances only)."""
    cam = pinhole or world.camera.wide()
    view = view_matrix_gl(cam_T_world)
    s = world.camera.supersample
    flags = p.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX
    if s == 1:
        rgb, depth_buf, seg = _raw(world, cam.width_px, cam.height_px, view, cam.projection_matrix_gl(1), flags)
    else:
        # Anti-aliased colour from a supersampled render; exact depth/instance from an
        # output-resolution render whose samples sit at the output pixel centres.
        if with_rgb:
            hi, _, hseg = _raw(
                world, cam.width_px * s, cam.height_px * s, view, cam.projection_matrix_gl(s), p.ER_NO_SEGMENTATION_MASK
            )
            rgb = hi.reshape(cam.height_px, s, cam.width_px, s, 3).mean(axis=(1, 3)).round().astype(np.uint8)
        _, depth_buf, seg = _raw(world, cam.width_px, cam.height_px, view, cam.projection_matrix_gl(1), flags)
    if not with_rgb:
        rgb = None
    obj = np.where(seg >= 0, seg & 0xFFFFFF, -1)
    lut = world.instance_lut
    instance = np.where(obj >= 0, lut[np.clip(obj, 0, len(lut) - 1)], -1).astype(np.int32)
    part_lut = world.part_lut
    part = None
    if part_lut is not None:
        part = np.where(obj >= 0, part_lut[np.clip(obj, 0, len(part_lut) - 1)], -1).astype(np.int32)
    depth = cam.linear_depth(depth_buf)
    depth[instance < 0] = cam.far_m
    return Render(rgb=rgb, depth_m=depth, instance=instance, part=part)


def _raw(world, w: int, h: int, view, proj, flags):
    _, _, rgba, depth, seg = world.client.getCameraImage(
        w,
        h,
        view,
        proj,
        renderer=p.ER_TINY_RENDERER,
        flags=flags,
        shadow=0,
        lightDirection=list(world.light_direction),
        lightAmbientCoeff=0.6,
        lightDiffuseCoeff=0.5,
        lightSpecularCoeff=0.05,
    )
    rgb = np.asarray(rgba, np.uint8).reshape(h, w, 4)[..., :3].copy()
    seg = np.asarray(seg, np.int64).reshape(h, w)
    if flags != p.ER_NO_SEGMENTATION_MASK:
        sky = seg < 0
    else:
        sky = np.asarray(depth).reshape(h, w) >= 1.0
    if (h, w) not in world._sky:  # one per render size (each view, and supersampled renders)
        world._sky[(h, w)] = textures.sky_gradient(h, w, h * 0.5)
    rgb[sky] = world._sky[(h, w)][sky]
    return rgb, np.asarray(depth, np.float32).reshape(h, w), seg
