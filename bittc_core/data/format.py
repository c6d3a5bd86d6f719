"""The on-disk dataset format (version 1). Readable with numpy, json and any PNG reader.

Layout::

    DIR/
      generation.yaml         resolved generation config shared by every split
      dataset_card.json       counts, tau histogram over actor pixels, config
      manifest.jsonl          one line per sample: split, index, seed, path, frames
      train/000000/           one folder per sample (also val/, test/)
        frame_0.png ...       K frames, RGB 8-bit, oldest first (frame_{K-1} is the latest)
        gt.npz                ground truth of each consecutive pair j -> j+1, leading dim K-1:
                                eta      float32 (K-1, H, W)  Z(t_{j+1}) / Z(t_j)
                                tau_s    float32 (K-1, H, W)  TTC from frame j+1's capture [s], +inf at eta = 1
                                depth_m  float32 (K-1, H, W)  depth Z of frame j+1 [m]
                                flow_px  float32 (K-1, H, W, 2) (u, v) = position in j+1 - position in j [px]
                                instance int16   (K-1, H, W)  -1 sky, 0 static, >0 vehicle
                                valid    bool    (K-1, H, W)  exact ground truth available
        meta.json             intrinsics (px), dt_s, camera, road, actors, per-frame ego/actor states,
                              sample seed, tau histogram of this sample

Maps live in the later frame's pixel grid of each pair. A sample folder appears
atomically: it is written under a temporary name and renamed when complete.
"""

from __future__ import annotations

import json
import os
import shutil
import zipfile
from pathlib import Path

import cv2
import numpy as np

from bittc_core.data.npz_writer import save_npz

FORMAT_VERSION = 1
SPLITS = ("train", "val", "test")
GT_KEYS = {
    "eta": np.float32,
    "tau_s": np.float32,
    "depth_m": np.float32,
    "flow_px": np.float32,
    "instance": np.int16,
    "valid": np.bool_,
}
# tau histogram bin edges [s] over actor pixels; plus "below", "above" and "inf" (receding at eta == 1)
TAU_BIN_EDGES_S = (-10.0, -5.0, -3.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0)


def sample_dirname(index: int) -> str:
    return f"{index:06d}"


def tau_bin_labels() -> list[str]:
    e = TAU_BIN_EDGES_S
    return ["< -10", *[f"[{e[i]:g}, {e[i + 1]:g})" for i in range(len(e) - 1)], ">= 10", "inf"]


def tau_histogram(tau_s: np.ndarray, mask: np.ndarray) -> dict[str, int]:
    """Counts of ``tau_s[mask]`` in TAU_BIN_EDGES_S bins, plus below/above/inf."""
    t = tau_s[mask]
    inf = np.isinf(t)
    finite = t[~inf]
    counts, _ = np.histogram(finite, bins=np.asarray(TAU_BIN_EDGES_S))
    edges = TAU_BIN_EDGES_S
    values = [
        int((finite < edges[0]).sum()),
        *(int(c) for c in counts),
        int((finite >= edges[-1]).sum()),
        int(inf.sum()),
    ]
    return dict(zip(tau_bin_labels(), values))


def write_sample(split_dir: Path, index: int, clip, extra_meta: dict) -> None:
    """Write one sample folder atomically (temporary folder, then rename)."""
    final = split_dir / sample_dirname(index)
    tmp = split_dir / f".tmp-{sample_dirname(index)}-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    for k, img in enumerate(clip.images):
        ok, png = cv2.imencode(".png", cv2.cvtColor(img, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, 1])
        if not ok:
            raise OSError(f"PNG encoding failed for sample {index}")
        (tmp / f"frame_{k}.png").write_bytes(png.tobytes())
    arrays = {key: np.stack([getattr(g, key) for g in clip.gts]).astype(dt) for key, dt in GT_KEYS.items()}
    save_npz(tmp / "gt.npz", arrays)
    last = clip.gts[-1]
    meta = {
        **clip.meta,
        **extra_meta,
        "format_version": FORMAT_VERSION,
        "n_frames": len(clip.images),
        "tau_histogram_actor_px": tau_histogram(last.tau_s, last.valid & (last.instance > 0)),
    }
    (tmp / "meta.json").write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n")
    if final.exists():  # a damaged sample being regenerated
        shutil.rmtree(final)
    os.rename(tmp, final)


def sample_is_complete(sample_dir: Path, n_frames: int) -> bool:
    """Cheap integrity check used on resume: files present, meta parses, zip CRCs good."""
    try:
        meta = json.loads((sample_dir / "meta.json").read_text())
        if meta.get("format_version") != FORMAT_VERSION or meta.get("n_frames") != n_frames:
            return False
        for k in range(n_frames):
            if (sample_dir / f"frame_{k}.png").stat().st_size == 0:
                return False
        with zipfile.ZipFile(sample_dir / "gt.npz") as zf:
            if zf.testzip() is not None or {n[:-4] for n in zf.namelist()} != set(GT_KEYS):
                return False
        return True
    except (OSError, ValueError, zipfile.BadZipFile, KeyError):
        return False


def read_sample(sample_dir: Path) -> tuple[list[np.ndarray], dict[str, np.ndarray], dict]:
    """(frames RGB uint8 oldest first, ground-truth arrays, meta)."""
    meta = json.loads((sample_dir / "meta.json").read_text())
    frames = []
    for k in range(meta["n_frames"]):
        bgr = cv2.imread(str(sample_dir / f"frame_{k}.png"), cv2.IMREAD_COLOR)
        if bgr is None:
            raise OSError(f"cannot read {sample_dir / f'frame_{k}.png'}")
        frames.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
    with np.load(sample_dir / "gt.npz", allow_pickle=False) as z:
        gt = {k: z[k] for k in GT_KEYS}
    return frames, gt, meta
