"""Task operators P_phi of the paper: scale warp (TTC) and shift warp (binary flow).

Convention (pixel coordinates of the 1/3-resolution feature map, x to the right,
y down, pixel centres at integers, image centre c = ((w-1)/2, (h-1)/2)):
    * scale warp:  warped_src(x) = src(c + eta_i * (x - c))      (eta_i = 1: identity)
    * column warp: warped_src(x, y) = src(x, c_y + eta_i * (y - c_y))  (rows only)
    * shift warp:  warped_src(x) = src(x - s_i),  s_i = (u_i, v_i) / 3  [feature px]
Both sample bilinearly with zeros outside ``src``. The output lives on the *padded*
grid (``PaddedGrid``): the feature map zero-padded to ``pad_factor`` times its size,
so that content scaled or shifted past the border is not cropped out (paper Sec. 4.3).
Padded pixel (i, j) is original pixel (i - top, j - left).

The column warp aligns what keeps its bearing while it nears: a road user on a collision
course grows about its own column, not about the image centre (``model.correlation``).

Why: a point seen at x_latest was at x_prev = c + eta (x_latest - c) when it expands
about the centre with motion-in-depth eta, and at x_prev = x_latest - (u, v) when it
moves by the flow (u, v); the warp aligns the previous (source) frame to the latest
(reference) one exactly when the hypothesis matches the truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
import torch.nn.functional as F


@dataclass(frozen=True)
class PaddedGrid:
    """An (h, w) map centred in an (hp, wp) zero-padded map."""

    h: int
    w: int
    hp: int
    wp: int
    top: int
    left: int

    @classmethod
    def for_features(cls, h: int, w: int, pad_factor: float, multiple: int) -> PaddedGrid:
        hp = math.ceil(h * pad_factor / multiple) * multiple
        wp = math.ceil(w * pad_factor / multiple) * multiple
        return cls(h, w, hp, wp, (hp - h) // 2, (wp - w) // 2)

    def pad(self, x: torch.Tensor) -> torch.Tensor:
        """Zero-pad (..., h, w) -> (..., hp, wp)."""
        bottom = self.hp - self.h - self.top
        right = self.wp - self.w - self.left
        return F.pad(x, (self.left, right, self.top, bottom))

    def crop(self, x: torch.Tensor) -> torch.Tensor:
        """Inverse of ``pad``: (..., hp, wp) -> (..., h, w)."""
        return x[..., self.top : self.top + self.h, self.left : self.left + self.w]

    def base_grid(self, device: torch.device, dtype: torch.dtype) -> torch.Tensor:
        """(hp, wp, 2) normalised (x, y) of padded pixels in the original map
        (align_corners=True: -1 and +1 are the centres of the border pixels)."""
        xs = (torch.arange(self.wp, device=device, dtype=dtype) - self.left) * (2.0 / max(self.w - 1, 1)) - 1.0
        ys = (torch.arange(self.hp, device=device, dtype=dtype) - self.top) * (2.0 / max(self.h - 1, 1)) - 1.0
        gy, gx = torch.meshgrid(ys, xs, indexing="ij")
        return torch.stack((gx, gy), dim=-1)


def _repeat_per_hypothesis(src: torch.Tensor, k: int) -> torch.Tensor:
    """(B, C, h, w) -> (B*K, C, h, w), batch-major."""
    b, c, h, w = src.shape
    return src[:, None].expand(b, k, c, h, w).reshape(b * k, c, h, w)


def _warp_about_centre(
    src: torch.Tensor, eta: torch.Tensor, grid: PaddedGrid, unpadded: bool, columns_in_place: bool
) -> torch.Tensor:
    """``src`` sampled at c + eta (x - c) for each eta (B, K), in both coordinates or, with
    ``columns_in_place``, in y only (shapes: ``scale_warp``)."""
    b, k = eta.shape
    base = grid.base_grid(src.device, src.dtype)  # (hp, wp, 2): normalised (x, y), centred
    if unpadded:
        base = base[grid.top : grid.top + grid.h, grid.left : grid.left + grid.w]
    # normalised coords are centred on c, so c + eta (x - c) -> eta * n(x)
    scale = eta.reshape(b * k, 1, 1, 1).to(src.dtype)
    if columns_in_place:
        y = scale * base[..., 1:]
        sample = torch.cat([base[..., :1].expand_as(y), y], dim=-1)
    else:
        sample = scale * base
    src_k = src if src.shape[0] == b * k else _repeat_per_hypothesis(src, k)
    return F.grid_sample(src_k, sample, mode="bilinear", padding_mode="zeros", align_corners=True)


def scale_warp(src: torch.Tensor, eta: torch.Tensor, grid: PaddedGrid, unpadded: bool = False) -> torch.Tensor:
    """Scale ``src`` (B, C, h, w), or one source per hypothesis (B*K, C, h, w, batch-major),
    about its centre for each eta (B, K) -> (B*K, C, hp, wp), or only the unpadded part of
    that, (B*K, C, h, w), with ``unpadded``."""
    return _warp_about_centre(src, eta, grid, unpadded, columns_in_place=False)


def column_warp(src: torch.Tensor, eta: torch.Tensor, grid: PaddedGrid, unpadded: bool = False) -> torch.Tensor:
    """``scale_warp`` with each column sampled where it stands: the rows scaled about the
    centre row by each eta (B, K); shapes as ``scale_warp``'s."""
    return _warp_about_centre(src, eta, grid, unpadded, columns_in_place=True)


def shift_warp(src: torch.Tensor, shift_feat: torch.Tensor, grid: PaddedGrid) -> torch.Tensor:
    """Shift ``src`` (B, C, h, w) by (u, v) [feature px] for each of (B, K, 2) -> (B*K, C, hp, wp)."""
    b, k, _ = shift_feat.shape
    base = grid.base_grid(src.device, src.dtype)
    scale = torch.tensor([2.0 / max(grid.w - 1, 1), 2.0 / max(grid.h - 1, 1)], device=src.device, dtype=src.dtype)
    offset = shift_feat.reshape(b * k, 1, 1, 2).to(src.dtype) * scale
    return F.grid_sample(
        _repeat_per_hypothesis(src, k), base - offset, mode="bilinear", padding_mode="zeros", align_corners=True
    )
