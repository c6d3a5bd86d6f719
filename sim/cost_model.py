"""Device cost models: what one closed-loop job computed (``JobWork``) and what a device
charges for it (``CostTerms`` per estimator family, collected in a ``DeviceProfile``).
Pure Python. The formula and its terms: ``sim.latency``; the files: ``sim.profile_file``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bittc_core.errors import ConfigError


class LatencyError(ConfigError):
    """A malformed latency mode, an unknown profile, or a latency that is not a time."""


COST_FAMILIES = ("bittc", "flow")  # estimator families a profile prices
COST_TERMS = ("extract_ms", "view_ms", "threshold_ms", "job_ms")


@dataclass(frozen=True)
class JobWork:
    """What one job computed, as a device profile prices it (see the module docstring).

    Each view counts one in ``views`` (its fixed cost: on a CPU the network's many small
    operations cost about the same at any size), while its thresholds and extractions count
    in wide-view equivalents: a view of fewer pixels than the wide view (the fovea, half
    as wide by default) counts as its pixel share of one (``of_views``)."""

    estimator: str | None  # a COST_FAMILIES member, or None (no estimator: the oracle, none)
    views: int = 1  # camera views the estimator ran on (wide, fovea)
    thresholds: float = 0  # thresholds evaluated, summed over the views, in wide-view equivalents
    extractions: float = 0  # frames x views through the feature extractor, in wide-view equivalents

    @classmethod
    def of_views(
        cls, view_thresholds: dict, pixel_share: dict, estimator: str | None, extractions_per_view: int
    ) -> JobWork:
        """view -> thresholds run on it, view -> its pixels over the wide view's, and the
        frames each view extracted -> the job's work."""
        share = [pixel_share[v] for v in view_thresholds]
        return cls(
            estimator,
            len(share),
            _sum(k * w for k, w in zip(view_thresholds.values(), share)),
            _sum(extractions_per_view * w for w in share),
        )


def _sum(values) -> float | int:
    """A sum kept an int where every term is whole (the bytes of traces of full-size views)."""
    total = sum(values)
    return int(total) if float(total).is_integer() else round(float(total), 6)


def pixel_shares(calibration) -> dict[str, float]:
    """View -> its pixel count over the wide view's (``controllers.base.Calibration.views``)."""
    views = calibration.views
    wide = views["wide"].width_px * views["wide"].height_px
    return {v: c.width_px * c.height_px / wide for v, c in views.items()}


@dataclass(frozen=True)
class CostTerms:
    """One estimator family's cost terms [ms] on one device."""

    extract_ms: float = 0.0  # [ms] per feature extraction (one frame, one view)
    view_ms: float = 0.0  # [ms] per view per job, independent of K
    threshold_ms: float = 0.0  # [ms] per threshold per view
    job_ms: float = 0.0  # [ms] per job

    def latency_ms(self, work: JobWork) -> float:
        return (
            self.job_ms
            + work.views * self.view_ms
            + work.thresholds * self.threshold_ms
            + work.extractions * self.extract_ms
        )


@dataclass(frozen=True)
class DeviceProfile:
    """Cost terms per estimator family on one device (continuous mode: ``continuous_ms``)."""

    name: str
    costs: dict  # family -> CostTerms
    source: str  # where the numbers come from
    measured: bool  # True when measured on the device, False when scaled or assumed
    continuous_ms: float | None = None  # [ms] one continuous-TTC call of the network, where known

    def latency_ms(self, work: JobWork) -> float:
        if work.estimator is None:
            return 0.0
        if work.estimator not in self.costs:
            raise LatencyError(
                f"profile {self.name!r} prices {', '.join(sorted(self.costs))}, not the {work.estimator!r} estimator"
            )
        return self.costs[work.estimator].latency_ms(work)

    def stream_ms(self, family: str, num_alphas: int, views: int = 1) -> float:
        """[ms] one steady-stream job (one extraction per view) with K thresholds."""
        return self.latency_ms(JobWork(family, views, views * num_alphas, views if family == "bittc" else 0))


def parse_costs(where: str, raw: dict) -> dict:
    """{family: {term: ms}} of a profile -> family -> CostTerms; refused by name when a family
    or term is unknown, a term is missing or a number is negative or not finite."""
    out = {}
    for fam in COST_FAMILIES:
        if fam not in raw:
            continue
        terms = raw[fam]
        if not isinstance(terms, dict) or set(terms) != set(COST_TERMS):
            raise LatencyError(f"{where}: {fam} needs exactly the cost terms {list(COST_TERMS)} [ms], got {terms!r}")
        for key, v in terms.items():
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0):
                raise LatencyError(f"{where}: {fam}.{key} = {v!r} must be a finite number >= 0")
        out[fam] = CostTerms(**{k: float(v) for k, v in terms.items()})
    if not out:
        raise LatencyError(f"{where}: needs the cost terms of at least one of {list(COST_FAMILIES)}")
    return out
