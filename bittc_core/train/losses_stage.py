"""The losses of a training stage on one batch (paper Sec. 4.4 and Supp. B; the stages
are described in :mod:`bittc_core.train.loop`).

Shapes: images (B, 3, H, W); ``eta``, ``instance``, masks (B, H, W); thresholds (B, T) in
eta; logits (B, T, H, W). eta is the motion in depth of the latest frame against the
previous one (``bittc_core.ttc``).
"""

from __future__ import annotations

import math

import torch

from bittc_core.model import BinaryTTCNet
from bittc_core.train.config import TrainConfig
from bittc_core.train.distill import flip_averaged_logits
from bittc_core.train.losses import lovasz_two_class, masked_bce, masked_smooth_l1
from bittc_core.train.targets import (
    INPATH_THRESHOLD_JITTER,
    eta_labels,
    near_outside,
    sample_eta,
    sample_eta_at_pixels,
    sample_shifts_px,
    shift_labels,
    valid_mask,
)


def binary_thresholds(c: TrainConfig, batch: dict, mask: torch.Tensor, dt_s: float, gen: torch.Generator):
    """(B, thresholds_per_pair) eta thresholds of a binary-stage batch: the pixel share at
    valid pixels' eta, then the in-path share at in-path vehicle pixels' eta, the rest
    uniform (``train.targets``)."""
    eta, k = batch["eta"], c.thresholds_per_pair
    thr = sample_eta(eta.shape[0], k, c.train_tau_min_s, c.train_eta_max, dt_s, gen)
    at_pixels = round(k * c.pixel_threshold_share)
    if at_pixels:
        thr[:, :at_pixels] = sample_eta_at_pixels(eta, mask, at_pixels, c.train_tau_min_s, c.train_eta_max, dt_s, gen)
    at_inpath = min(round(k * c.inpath_threshold_share), k - at_pixels)
    if at_inpath and "inpath" in batch:  # the built-in synthetic data has no road, no path
        thr[:, at_pixels : at_pixels + at_inpath] = sample_eta_at_pixels(
            eta,
            mask & batch["inpath"],
            at_inpath,
            c.train_tau_min_s,
            c.train_eta_max,
            dt_s,
            gen,
            INPATH_THRESHOLD_JITTER,
        )
    return thr


def _taught_pixels(c: TrainConfig, batch: dict) -> torch.Tensor:
    """(B, 1, H, W) the pixels whose labels the teacher's maps replace (``distill_scope``):
    scenery (instance 0), with "scenery-vehicles" also vehicles (every class but the road users)."""
    if c.distill_scope == "scenery":
        return (batch["instance"] == 0)[:, None]
    if "actor_class" not in batch:
        raise ValueError(f"distill_scope {c.distill_scope!r} needs the dataset's actor classes (actor_class)")
    return (batch["actor_class"] < 2)[:, None]  # 0 none, 1 vehicle; 2 pedestrian, 3 cyclist learn the labels


def _labels_from_teacher(
    c: TrainConfig,
    batch: dict,
    mask: torch.Tensor,
    logits: torch.Tensor,
    labels: torch.Tensor,
    soft: torch.Tensor,
    weight: torch.Tensor | None,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``distill_scope`` "scenery" or "scenery-vehicles": on ``_taught_pixels`` the teacher's
    soft maps replace the ground-truth labels and their BCE weight is times ``distill_weight``
    (relative to the ground-truth pixels: the BCE is a weighted mean); the Lovasz term reads
    the teacher's maps rounded at 0.5 there, unweighted. Elsewhere the ground truth stays.
    -> (labels, weight, the BCE towards the teacher on the taught pixels, pixel-weighted as
    the "all" scope logs it)."""
    taught = _taught_pixels(c, batch)
    base = weight if weight is not None else torch.ones_like(batch["eta"])[:, None]
    log = masked_bce(logits.detach(), soft, mask[:, None] & taught, base)
    return torch.where(taught, soft, labels), torch.where(taught, c.distill_weight * base, base), log


def stage_losses(
    net: BinaryTTCNet,
    c: TrainConfig,
    batch: dict,
    gen: torch.Generator,
    device: torch.device,
    teacher: BinaryTTCNet | None = None,
) -> dict[str, torch.Tensor]:
    """The losses of one batch for the stage of ``c`` (see :mod:`bittc_core.train.loop`):
    ``loss`` (what is minimised) and its parts (``flow``, ``ttc``, ``iou``, ``distill``,
    ``cont``) for the log. ``gen`` draws the thresholds and shifts; ``teacher``: the
    frozen network distilled from."""
    mc = net.config
    b = batch["image_prev"].shape[0]
    feats = net.extract(torch.cat((batch["image_prev"], batch["image_latest"])))
    ctx = net.prepare_reference(feats[b:], batch["image_latest"])
    mask = valid_mask(batch)
    if c.freeze_binary:  # nothing the flow heads feed can learn
        out = {"flow": torch.zeros((), device=device)}
    else:
        shifts = sample_shifts_px(b, c.shifts_per_pair, mc.max_shift_px, gen).to(device)
        flow_logits = net.classify_shift(ctx, feats[:b], shifts)
        out = {"flow": masked_bce(flow_logits, shift_labels(batch["flow_px"], shifts), mask[:, None, None])}
    if c.stage == "flow":
        out["loss"] = out["flow"]
        return out
    eta = batch["eta"]
    if c.stage == "binary":
        thr = binary_thresholds(c, batch, mask, mc.frame_dt_s, gen).to(device)
        logits = net.classify_eta(ctx, feats[:b], thr)
        weight = None
        if c.actor_weight != 1.0 or c.inpath_weight != 1.0 or c.vru_weight != 1.0:
            weight = torch.where(batch["instance"] > 0, c.actor_weight, 1.0)
            if "inpath" in batch:  # the built-in synthetic data has no road, no path
                weight = torch.where(batch["inpath"], c.inpath_weight, weight)
            if c.vru_weight != 1.0 and "actor_class" in batch:  # pedestrians (2) and cyclists (3)
                weight = torch.where(batch["actor_class"] >= 2, c.vru_weight, weight)
            weight = weight[:, None]
        if c.near_outside_weight != 1.0:  # scenery just outside each fence, per threshold
            base = weight if weight is not None else torch.ones_like(eta)[:, None]
            scenery = (batch["instance"] == 0)[:, None]
            weight = torch.where(near_outside(eta, thr) & scenery, c.near_outside_weight * base, base)
        labels = eta_labels(eta, thr)
        soft = None
        if teacher is not None:
            soft = torch.sigmoid(flip_averaged_logits(teacher, batch["image_prev"], batch["image_latest"], thr))
            if c.distill_scope != "all":
                labels, weight, out["distill"] = _labels_from_teacher(c, batch, mask, logits, labels, soft, weight)
        out["ttc"] = masked_bce(logits, labels, mask[:, None], weight)
        if c.lovasz_weight > 0:
            out["iou"] = lovasz_two_class(logits, labels.round(), mask[:, None])
            out["ttc"] = out["ttc"] + c.lovasz_weight * out["iou"]
        if soft is not None and c.distill_scope == "all":
            out["distill"] = masked_bce(logits, soft, mask[:, None], weight)
            out["ttc"] = out["ttc"] + c.distill_weight * out["distill"]
    else:
        cont = net.continuous(ctx, feats[:b])
        levels = cont.levels.expand(b, -1)
        bce = torch.nn.functional.binary_cross_entropy(
            cont.prob_le.clamp(1e-6, 1 - 1e-6)[mask[:, None].expand_as(cont.prob_le)],
            eta_labels(eta, levels)[mask[:, None].expand_as(cont.prob_le)],
        )
        target = torch.log(eta.clamp(mc.cont_eta_min, mc.cont_eta_max))[:, None]
        unit = math.log(mc.cont_eta_max / mc.cont_eta_min) / mc.cont_levels  # ~ one bin
        m = mask[:, None] & (eta[:, None] > 0)
        refined = masked_smooth_l1(cont.log_eta, target, m, unit)
        sl1 = 0.5 * (masked_smooth_l1(torch.log(cont.eta_auc), target, m, unit) + refined)
        out["cont"] = sl1
        out["ttc"] = c.cont_bce_weight * bce + c.cont_sl1_weight * sl1
        if c.freeze_binary:  # only the refined term has gradients; log the same parts
            out["loss"] = c.cont_sl1_weight * refined
            return out
    out["loss"] = c.ttc_weight * out["ttc"] + c.flow_weight * out["flow"]
    return out
