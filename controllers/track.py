"""A tracked region's observations and state (``controllers.tracker``): per job its columns,
its fence bound on the TTC, the ground's depth under it and the ego's odometry pose; per
track the side of the image centre it came from, whether it floats, is held or refuted.
Columns [px] in the view's pixel grid; times [s] on the run's clock; depths [m] along the
camera's axis."""

from __future__ import annotations

from dataclasses import dataclass, field

from controllers.base import Calibration
from controllers.road import static_depth_m


@dataclass
class Obs:
    """One job's region of a track: its capture time [s], its left and right columns [px],
    the smallest fence [s] that holds half of it, the ground's depth under it [m] where
    that shows, the ego's speed [m/s] and odometry pose then."""

    t_s: float
    u_left: float
    u_right: float
    tau_bound_s: float
    contact_depth_m: float | None
    speed_mps: float
    pose: tuple[float, float, float]  # odometry (x, y, psi) at t
    inner_px: float | None = None  # [px] its inner edge where read apart from its extent

    def across(self, cal: Calibration) -> bool:
        """Whether the region spans the image centre's column."""
        return self.u_left <= cal.cx_px <= self.u_right

    def inner_bearing(self, cal: Calibration, from_left: bool | None = None) -> float:
        """x / z of the region's inner edge (its column nearest the image centre; across
        the centre, with ``from_left`` known, its leading edge: the right one for a track
        that came from the left)."""
        if from_left is not None and self.across(cal):
            inner = self.u_right if from_left else self.u_left
        elif self.inner_px is not None:
            inner = self.inner_px
        else:
            inner = self.u_right if self.u_right < cal.cx_px else self.u_left
        return (inner - cal.cx_px) / cal.fx_px


@dataclass
class Track:
    obs: list[Obs] = field(default_factory=list)
    missed: int = 0
    refuted: bool = False  # a finer view found its bearing moving out: it predicts no more
    held: int = 0  # [jobs] left in which it counts as predicted though its prediction fails
    floating: bool = False  # its latest region does not reach a fence's lowest counted rows
    # the side of the image centre (True: the left) of its latest region not across the
    # centre, also when that region has left the window
    last_side: bool | None = None
    first_psi: float | None = None  # [rad] the ego's heading at its first region

    @property
    def centre_px(self) -> float:
        return 0.5 * (self.obs[-1].u_left + self.obs[-1].u_right)

    @property
    def width_px(self) -> float:
        return self.obs[-1].u_right - self.obs[-1].u_left + 1

    def side(self, cal: Calibration, keep: bool) -> bool | None:
        """With ``keep``, the side of the image centre it came from (True: the left), read
        on its earliest region in the window not across the centre, or, when every region
        in the window lies across it, on its last region before them; None without
        ``keep`` or when it was first seen across the centre and has stayed there."""
        if not keep:
            return None
        for o in self.obs:
            if not o.across(cal):
                return o.u_right < cal.cx_px
        return self.last_side

    def contact_time_s(self) -> float:
        """t0 [s]: the earliest time by which the track reaches the camera plane."""
        return min(o.t_s + o.tau_bound_s for o in self.obs)

    def width_m(self, cal: Calibration) -> float:
        """[m] its latest region's width at the static depth of that region's fence."""
        o = self.obs[-1]
        return (o.u_right - o.u_left + 1) / cal.fx_px * static_depth_m(cal, o.speed_mps, o.tau_bound_s)
