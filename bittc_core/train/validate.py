"""Validation during training: mean IoU of the stage's binary maps on a few pairs.

binary / continuous stages: TTC mIoU with the Table 1 thresholds (``metrics``), plus MiD
from the continuous output in the continuous stage. flow stage: two-class IoU of
p(u > u_i), p(v > v_i) for fixed shifts ``FLOW_VAL_SHIFTS_PX``.
"""

from __future__ import annotations

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset, Subset

from bittc_core.metrics import class_counts, inside_geofence, mid_terms, miou_thresholds_s, two_class_iou
from bittc_core.model import BinaryTTCNet
from bittc_core.train.targets import valid_mask
from bittc_core.ttc import tau_to_eta

FLOW_VAL_SHIFTS_PX = (-9.0, 0.0, 9.0)


@torch.inference_mode()
def validate(
    net: BinaryTTCNet, dataset: Dataset, *, stage: str, limit: int, batch_size: int, device: torch.device
) -> dict:
    was_training = net.training
    net.eval()
    subset = Subset(dataset, range(min(limit, len(dataset))))
    dt_s = net.config.frame_dt_s
    taus = miou_thresholds_s(dt_s)
    eta_thr = torch.tensor(tau_to_eta(taus, dt_s), dtype=torch.float32, device=device)
    shifts = torch.tensor([[s, s] for s in FLOW_VAL_SHIFTS_PX], device=device)
    ious, mid_sum, mid_n = [], 0.0, 0
    for batch in DataLoader(subset, batch_size=batch_size):
        batch = {k: v.to(device) for k, v in batch.items()}
        b = batch["image_prev"].shape[0]
        feats = net.extract(torch.cat((batch["image_prev"], batch["image_latest"])))
        ctx = net.prepare_reference(feats[b:], batch["image_latest"])
        mask = valid_mask(batch).cpu().numpy()
        if stage == "flow":
            pred = (net.classify_shift(ctx, feats[:b], shifts.expand(b, -1, -1)) > 0).cpu().numpy()
            flow = batch["flow_px"].cpu().numpy()
            for i in range(b):
                per = [
                    two_class_iou(class_counts(pred[i, k, a], flow[i, a] > s[a], mask[i]))
                    for k, s in enumerate(shifts.tolist())
                    for a in (0, 1)
                ]
                ious.append(np.nanmean(per))
            continue
        pred = (net.classify_eta(ctx, feats[:b], eta_thr.expand(b, -1)) > 0).cpu().numpy()
        eta = batch["eta"].cpu().numpy()
        for i in range(b):
            per = [
                two_class_iou(class_counts(pred[i, k], inside_geofence(eta[i], float(e)), mask[i]))
                for k, e in enumerate(eta_thr.tolist())
            ]
            ious.append(np.nanmean(per))
        if stage == "continuous":
            eta_hat = torch.exp(net.continuous(ctx, feats[:b]).log_eta)[:, 0].cpu().numpy()
            for i in range(b):
                s, n = mid_terms(eta_hat[i], eta[i], mask[i])
                mid_sum, mid_n = mid_sum + s, mid_n + n
    net.train(was_training)
    return {
        "val_miou": float(np.nanmean(ious)) if ious else float("nan"),
        "val_mid": mid_sum / mid_n * 1e4 if mid_n else float("nan"),
    }
