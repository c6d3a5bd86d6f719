"""The wide view and the fovea side by side in one map: one SegNet pass for both views' fences?

Usage: python bench/bench_fovea_side_by_side.py [--rounds N] [--threads T]

The network's streaming work of a controller job at K = 4 (0.8, 1.21, 1.84, 2.8 s, the
frame stride 3 pair), times in interleaved rounds:

* ``wide alone``: extract the new 96x288 frame, its reference context, the four fences;
* ``two passes`` (as the estimator runs it): the same, and for the 96x144 fovea its own
  extraction, reference and its two fences (1.84 and 2.8 s);
* ``side by side``: both views extracted apart, then the two views' zero-padded feature
  maps placed side by side in one map (48x144 and 48x80 -> 48x224 at K = 4's padding), so
  that the 1.84 and 2.8 s fences of both views go through SegNet and the refiner in one
  call each (the fovea's correlation volume placed where its padded grid puts it); the
  0.8 and 1.21 s fences on the wide view alone;
* ``side by side, all four``: every fence on the joint map (the fovea's two smaller fences
  computed and thrown away), one SegNet call in all.

Where the two maps meet, the deeper layers see the other view's padding instead of
zeros, so the side-by-side fences are not exactly the separate ones; this script measures
only their cost. Prints the medians and the ratios to the wide view alone.
"""

from __future__ import annotations

import argparse

import numpy as np
import torch
import torch.nn.functional as F

from bittc_core.benchmark import interleaved_median_ms
from bittc_core.estimator import make_estimator
from bittc_core.model.segnet import ReferenceTerms, SegNetInputs
from bittc_core.model.warp import PaddedGrid
from bittc_core.ttc import tau_to_eta
from controllers.geofence import default_thresholds

H, WIDE_W, FOVEA_W = 96, 288, 144  # [px]
FRAME_STRIDE = 3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    est = make_estimator("bittc", device="cpu")
    net, cfg, cl = est.net, est.net.config, torch.channels_last
    tau = np.asarray(default_thresholds(4)) / FRAME_STRIDE  # [s] in the network's 0.1 s time base
    thr = torch.tensor(tau_to_eta(tau, est.dt_s), dtype=torch.float32)[None]
    grids = [PaddedGrid.for_features(H // 3, w // 3, cfg.pad_factor, cfg.down_factor) for w in (WIDE_W, FOVEA_W)]
    gw, gf = grids
    # the joint map: the padded maps side by side, its "unpadded" span from the wide map's first
    # column to the fovea map's last (the padding between them inside it)
    gap = gw.wp - gw.left - gw.w + gf.left  # [feature px] between the two unpadded maps
    joint = PaddedGrid(gw.h, gw.w + gap + gf.w, gw.hp, gw.wp + gf.wp, gw.top, gw.left)

    def image(w: int) -> torch.Tensor:
        return torch.rand(1, 3, H, w).contiguous(memory_format=cl)

    def refined(coarse: torch.Tensor, guide: torch.Tensor, size_hw) -> list[torch.Tensor]:
        up = F.interpolate(coarse, size=size_hw, mode="bilinear", align_corners=False)
        return [net.refine(guide, up[i : i + 1]) for i in range(up.shape[0])]

    def side_by_side(prev: list[torch.Tensor], all_four: bool) -> None:
        images = [image(WIDE_W), image(FOVEA_W)]
        feats = [net.extract(x) for x in images]
        ref = torch.cat([g.pad(f) for g, f in zip(grids, feats)], dim=3).contiguous(memory_format=cl)
        first = net.segnet.first_ref(ref)
        pad_image = torch.full((1, 3, H, 3 * gap), 0.5)  # grey: zero after the refiner's normalisation
        guide = net.refine.guide(torch.cat([images[0], pad_image, images[1]], dim=3).contiguous(memory_format=cl))
        shared = thr if all_four else thr[:, 2:]
        if not all_four:  # the smaller fences on the wide view alone
            inputs = net.scale_inputs(feats[0], prev[0], thr[:, :2], gw)
            terms = ReferenceTerms(first=first[..., : gw.wp // 2], skip=None, feat=None)
            refined(net.segnet(terms, inputs, gw)[:, :1], net.refine.guide(images[0]), (H, WIDE_W))
        parts = [net.scale_inputs(f, p, shared, g) for f, p, g in zip(feats, prev, grids)]
        warped = torch.cat([p.warped for p in parts], dim=3).contiguous(memory_format=cl)
        zeros = parts[0].corr.new_zeros(*parts[0].corr.shape[:3], gap)
        corr = torch.cat([parts[0].corr, zeros, parts[1].corr], dim=3).contiguous(memory_format=cl)
        logits = net.segnet(ReferenceTerms(first=first, skip=None, feat=None), SegNetInputs(warped, corr), joint)
        coarse = torch.cat(
            [
                F.interpolate(logits[:, :1, :, : gw.w], size=(H, WIDE_W), mode="bilinear", align_corners=False),
                logits.new_zeros(logits.shape[0], 1, H, 3 * gap),
                F.interpolate(logits[:, :1, :, -gf.w :], size=(H, FOVEA_W), mode="bilinear", align_corners=False),
            ],
            dim=3,
        )
        for i in range(coarse.shape[0]):
            net.refine(guide, coarse[i : i + 1])

    def separate(prev: list[torch.Tensor], views: int) -> None:
        for w, p, eta in list(zip((WIDE_W, FOVEA_W), prev, (thr, thr[:, 2:])))[:views]:
            x = image(w)
            f = net.extract(x)
            net.classify_eta(net.prepare_reference(f, x), p, eta)

    with torch.inference_mode():
        prev = [net.extract(image(w)) for w in (WIDE_W, FOVEA_W)]
        calls = {
            "wide alone": lambda a, b: separate(prev, 1),
            "two passes": lambda a, b: separate(prev, 2),
            "side by side": lambda a, b: side_by_side(prev, False),
            "side by side, all four": lambda a, b: side_by_side(prev, True),
        }
        med = interleaved_median_ms(calls, list(range(args.rounds + 4)), warmup=3)  # rounds by index
    print(f"96x288 wide, 96x144 fovea x4, K = 4, {args.threads} threads, {args.rounds} interleaved rounds")
    for k, v in med.items():
        print(f"  {k:<24} {v:7.2f} ms  {v / med['wide alone']:5.2f} x wide")


if __name__ == "__main__":
    main()
