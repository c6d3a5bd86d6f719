"""PyTorch Dataset over the generated format (see :mod:`bittc_core.data.format`).

Each item is one frame pair (by default the last pair of the clip), as a dict:

    image_prev, image_latest  float32 (3, H, W) in [0, 1]
    eta                       float32 (H, W)   Z(latest) / Z(prev)
    tau_s                     float32 (H, W)   TTC from the latest capture [s], +inf at eta = 1
    flow_px                   float32 (2, H, W) (u, v) = latest - previous position [px]
    valid                     bool    (H, W)
    instance                  int64   (H, W)   -1 sky, 0 static, > 0 actor (vehicle or road user)
    actor_class               int64   (H, W)   0 none, 1 car (any vehicle), 2 pedestrian, 3 cyclist
                                               (``class_map``; bittc_core.metrics.ACTOR_CLASSES)
    inpath                    bool    (H, W)   vehicle pixels within INPATH_HALF_WIDTH_M of the
                                               optical axis, nearer than INPATH_MAX_DEPTH_M
                                               times the view's zoom (a fovea sample's
                                               meta["view"]["zoom"], else 1: the same size
                                               in pixels)
    dt_s                      float32 ()       frame interval [s]
    intrinsics                float32 (4,)     fx, fy, cx, cy [px]
    ego_speed_mps             float32 ()       ego speed at the latest frame [m/s]

Augmentations that keep TTC valid (``augment=True``): horizontal flip (flow u and the
principal point flip with the image; eta and tau are unchanged), photometric changes
applied identically to both frames (brightness, contrast, gamma, colour gains), and an
optional crop centred on the principal point (``crop_hw``), so the scale warp's centre
stays where the model expects it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import Dataset

from bittc_core.data.format import SPLITS, read_sample
from bittc_core.errors import ConfigError
from bittc_core.metrics import ACTOR_CLASSES

INPATH_HALF_WIDTH_M = 1.5  # [m] |X| of the camera frame: the ego's half width plus a margin
INPATH_MAX_DEPTH_M = 80.0  # [m] at the wide view's focal; times the zoom for a fovea sample


class TTCDataset(Dataset):
    def __init__(
        self,
        root: str | Path,
        split: str,
        augment: bool = False,
        seed: int = 0,
        crop_hw: tuple[int, int] | None = None,
        pair: int | str = -1,
    ):
        self.root = Path(root)
        if split not in SPLITS:
            raise ConfigError(f"split {split!r}: must be one of {', '.join(SPLITS)}")
        manifest = self.root / "manifest.jsonl"
        if not manifest.exists():
            raise ConfigError(f"{str(self.root)!r}: no manifest.jsonl; is it a dataset made by `bittc generate`?")
        rows = [json.loads(line) for line in manifest.read_text().splitlines() if line.strip()]
        self.samples = [r for r in rows if r["split"] == split]
        if not self.samples:
            raise ConfigError(f"{str(self.root)!r}: the {split} split is empty")
        self.split = split
        self.augment = augment
        self.seed = seed
        self.crop_hw = crop_hw
        self.pair = pair
        self.epoch = 0

    def set_epoch(self, epoch: int) -> None:
        """Augmentations are drawn from (seed, epoch, index): call once per epoch."""
        self.epoch = epoch

    def __len__(self) -> int:
        return len(self.samples)

    def __getitem__(self, i: int) -> dict[str, torch.Tensor]:
        row = self.samples[i]
        frames, gt, meta = read_sample(self.root / row["path"])
        rng = np.random.default_rng([self.seed, self.epoch, row["index"], 7])
        n_pairs = len(frames) - 1
        j = int(rng.integers(n_pairs)) if self.pair == "random" else (self.pair % n_pairs)
        prev, latest = frames[j].astype(np.float32) / 255.0, frames[j + 1].astype(np.float32) / 255.0
        eta, tau, flow = gt["eta"][j], gt["tau_s"][j], gt["flow_px"][j].copy()
        valid, inst, depth = gt["valid"][j], gt["instance"][j].astype(np.int64), gt["depth_m"][j]
        intr = meta["intrinsics"]
        K = np.array([intr["fx_px"], intr["fy_px"], intr["cx_px"], intr["cy_px"]], np.float32)
        H, W = eta.shape
        if self.crop_hw is not None:
            ch, cw = self.crop_hw
            if ch > H or cw > W:
                raise ConfigError(f"crop_hw {self.crop_hw} is larger than the samples ({H}x{W})")
            y0 = int(round(K[3] - (ch - 1) / 2))
            x0 = int(round(K[2] - (cw - 1) / 2))
            y0, x0 = min(max(y0, 0), H - ch), min(max(x0, 0), W - cw)
            sl = (slice(y0, y0 + ch), slice(x0, x0 + cw))
            prev, latest, eta, tau, flow, valid, inst, depth = (
                a[sl] for a in (prev, latest, eta, tau, flow, valid, inst, depth)
            )
            K = K - np.array([0, 0, x0, y0], np.float32)
            H, W = ch, cw
        if self.augment:
            if rng.random() < 0.5:
                prev, latest, eta, tau, flow, valid, inst, depth = (
                    a[:, ::-1] for a in (prev, latest, eta, tau, flow, valid, inst, depth)
                )
                flow = flow * np.array([-1.0, 1.0], np.float32)
                K = K.copy()
                K[2] = W - 1 - K[2]
            gain = rng.uniform(0.9, 1.1, 3).astype(np.float32)
            bright, contrast, gamma = rng.uniform(-0.1, 0.1), rng.uniform(0.8, 1.2), rng.uniform(0.8, 1.25)
            prev, latest = (
                np.clip(((x**gamma) * gain - 0.5) * contrast + 0.5 + bright, 0.0, 1.0) for x in (prev, latest)
            )
        classes = class_map(inst, meta)
        lateral_m = np.abs(np.arange(W, dtype=np.float32) - K[2])[None, :] / K[0] * depth
        max_depth_m = INPATH_MAX_DEPTH_M * float(meta.get("view", {}).get("zoom", 1.0))
        inpath = (inst > 0) & valid & (lateral_m < INPATH_HALF_WIDTH_M) & (depth < max_depth_m)
        return {
            "image_prev": torch.from_numpy(np.ascontiguousarray(prev.transpose(2, 0, 1), np.float32)),
            "image_latest": torch.from_numpy(np.ascontiguousarray(latest.transpose(2, 0, 1), np.float32)),
            "eta": torch.from_numpy(np.ascontiguousarray(eta, np.float32)),
            "tau_s": torch.from_numpy(np.ascontiguousarray(tau, np.float32)),
            "flow_px": torch.from_numpy(np.ascontiguousarray(flow.transpose(2, 0, 1), np.float32)),
            "valid": torch.from_numpy(np.ascontiguousarray(valid, np.bool_)),
            "instance": torch.from_numpy(np.ascontiguousarray(inst, np.int64)),
            "actor_class": torch.from_numpy(np.ascontiguousarray(classes, np.int64)),
            "inpath": torch.from_numpy(np.ascontiguousarray(inpath, np.bool_)),
            "dt_s": torch.tensor(float(meta["dt_s"]), dtype=torch.float32),
            "intrinsics": torch.from_numpy(K.astype(np.float32)),
            "ego_speed_mps": torch.tensor(float(meta["frames"][j + 1]["ego"]["speed_mps"]), dtype=torch.float32),
        }


_CLASS_ID = {name: cid for cid, name in ACTOR_CLASSES.items()}


def class_map(instance: np.ndarray, meta: dict) -> np.ndarray:
    """(H, W) int64 actor class id per pixel (``ACTOR_CLASSES``; 0 for the static world and
    the sky) from the instance map and the sample's actors (meta.json): a road user's
    ``class``, every vehicle (car, GVT, van, truck) 'car' (``bittc_core.metrics.ACTOR_CLASSES``)."""
    lut = np.zeros(max([0, *(int(a["instance"]) for a in meta.get("actors", []))]) + 1, np.int64)
    for a in meta.get("actors", []):
        lut[int(a["instance"])] = _CLASS_ID[a.get("class", "car")]
    idx = np.clip(instance, 0, len(lut) - 1)
    return np.where(instance > 0, lut[idx], 0)
