"""The training loop of one stage (paper Sec. 4.4 and Supp. B).

Stages: ``flow``: binary-flow pre-training, TTC head unsupervised; ``binary``: binary
TTC (several eta thresholds per pair, vehicle (actor) pixels, moving or not, weighted
``actor_weight``; BCE,
plus ``lovasz_weight`` x a Lovasz surrogate of the per-map two-class IoU, plus
``distill_weight`` x BCE towards a frozen teacher's flip-averaged maps, actor pixels
weighted alike) + binary flow
auxiliary, weights 0.8 / 0.2;
``continuous``: the stacked TTC volume, BCE on its maps (0.1) + SmoothL1 on the AUC and
refined log eta (0.9), still with the flow auxiliary (0.8 / 0.2); with
``freeze_binary`` only ContRefineNet learns (SmoothL1 on the refined log eta).
AdamW, linear warm-up then cosine decay, gradient clipping; validation every
``val_every`` steps keeps the best checkpoint by val mIoU (by val MiD with
``freeze_binary``) at ``paths.best``; a
resumable checkpoint (optimizer, step, RNG states, the position in the epoch's data
order) goes to ``paths.last``, with
``keep_checkpoints`` the weights of every validation step to ``paths.snapshot``; a CSV
row every ``log_every`` steps to ``paths.csv``.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset, Sampler
from tqdm import tqdm

from bittc_core.atomic import write_text_atomic
from bittc_core.checkpoint import load_checkpoint, make_payload, save_checkpoint
from bittc_core.model import BinaryTTCNet
from bittc_core.train.config import TrainConfig
from bittc_core.train.distill import flip_averaged_logits
from bittc_core.train.losses import lovasz_two_class, masked_bce, masked_smooth_l1
from bittc_core.train.targets import (eta_labels, sample_eta, sample_eta_at_pixels, sample_shifts_px, shift_labels,
                                     valid_mask)
from bittc_core.train.validate import validate

# new columns go last, so a run resumed from an older log keeps its columns aligned
CSV_FIELDS = ("step", "stage", "loss", "loss_ttc", "loss_flow", "loss_cont", "lr", "grad_norm",
              "s_per_step", "val_miou", "val_mid", "loss_iou", "loss_distill")


@dataclass(frozen=True)
class RunPaths:
    """Files of a run, all beside the best checkpoint ``best`` (the --out path)."""

    best: Path
    last: Path
    csv: Path
    config: Path

    @classmethod
    def from_out(cls, out: str | Path) -> "RunPaths":
        out = Path(out)
        stem = out.with_suffix("")
        return cls(best=out, last=stem.with_name(stem.name + ".last.pt"),
                   csv=stem.with_suffix(".csv"), config=stem.with_name(stem.name + ".config.yaml"))

    def snapshot(self, stage: str, step: int) -> Path:
        """Where ``keep_checkpoints`` puts the weights of ``stage`` at ``step``."""
        stem = self.best.with_suffix("")
        return stem.with_name(f"{stem.name}.{stage}.step{step:06d}.pt")


class EpochSampler(Sampler[int]):
    """The training order: each epoch a permutation of the ``n`` pairs drawn from
    (``seed``, epoch) alone, so a resumed run can continue an epoch where it stopped.
    ``set_epoch(epoch, start)``: the next pass yields that epoch's order from its
    ``start``-th index on."""

    def __init__(self, n: int, seed: int) -> None:
        self.n, self.seed = n, seed
        self.epoch, self.start = 0, 0

    def set_epoch(self, epoch: int, start: int = 0) -> None:
        self.epoch, self.start = epoch, start

    def order(self, epoch: int) -> torch.Tensor:
        entropy = [self.seed & 0xFFFF_FFFF_FFFF_FFFF, epoch, 0x0DA7A]  # 0x0DA7A: this stream's tag
        gen = torch.Generator().manual_seed(int(np.random.SeedSequence(entropy).generate_state(1, np.uint64)[0]))
        return torch.randperm(self.n, generator=gen)

    def __iter__(self):
        return iter(self.order(self.epoch)[self.start:].tolist())

    def __len__(self) -> int:
        return self.n


def _forever(loader: DataLoader, epoch: int = 0, position: int = 0):
    """Endless ``(batch, epoch, position)`` from index ``position`` of ``epoch``'s order
    (``EpochSampler``) on; the returned (epoch, position) is where the next batch starts,
    what a checkpoint saved after this batch resumes at. Datasets with ``set_epoch``
    (TTCDataset) redraw augmentations per epoch."""
    n, b = len(loader.sampler), loader.batch_size
    while True:
        if hasattr(loader.dataset, "set_epoch"):
            loader.dataset.set_epoch(epoch)
        loader.sampler.set_epoch(epoch, position)
        for batch in loader:
            position += b
            # (drop_last: a rest shorter than a batch is dropped, the next batch opens the next epoch)
            yield (batch, epoch + 1, 0) if position + b > n else (batch, epoch, position)
        epoch, position = epoch + 1, 0


#: what ``freeze_binary`` freezes (their batch-norm statistics too): the binary network
BINARY_MODULES = ("features", "segnet", "refine")


def frozen_prefixes(cfg: TrainConfig) -> tuple[str, ...]:
    """Parameter-name prefixes that a stage of ``cfg`` does not train."""
    return tuple(f"{m}." for m in BINARY_MODULES) if cfg.freeze_binary else ()


def param_groups(net: torch.nn.Module, lr_mults: tuple[tuple[str, float], ...],
                 frozen: tuple[str, ...] = ()) -> list[dict]:
    """The trainable parameters (``requires_grad``, not under a ``frozen`` prefix) as AdamW
    groups, each with its ``lr_mult``: a parameter whose name starts with a prefix of
    ``lr_mults`` learns at that multiple of the scheduled rate (the longest matching
    prefix wins), every other one at 1x. A prefix that names no trainable parameter is an
    error (a typo would silently do nothing)."""
    groups: dict[float, list[torch.nn.Parameter]] = {}
    used = set()
    for name, q in net.named_parameters():
        if not q.requires_grad or name.startswith(frozen):
            continue
        match = max((p for p, _ in lr_mults if name.startswith(p)), key=len, default=None)
        used.add(match)
        groups.setdefault(dict(lr_mults)[match] if match else 1.0, []).append(q)
    unused = [p for p, _ in lr_mults if p not in used]
    if unused:
        raise ValueError(f"lr_mults: no trainable parameter name starts with {unused}")
    return [{"params": params, "lr_mult": mult} for mult, params in groups.items()]


class Trainer:
    def __init__(self, net: BinaryTTCNet, config_name: str, cfg: TrainConfig,
                 train_set: Dataset, val_set: Dataset, device: torch.device, paths: RunPaths,
                 meta: dict | None = None, teacher: BinaryTTCNet | None = None) -> None:
        if cfg.distill_weight > 0 and teacher is None:
            raise ValueError(f"distill_weight={cfg.distill_weight} needs a teacher network")
        if teacher is not None and cfg.distill_weight <= 0:
            raise ValueError("a teacher network needs distill_weight > 0")
        if teacher is not None and (teacher is net or teacher.config != net.config):
            raise ValueError("the teacher must be another network of the student's model config")
        self.net = net.to(device)
        # frozen, eval mode (its batch-norm statistics stay put)
        self.teacher = teacher.to(device).eval().requires_grad_(False) if teacher is not None else None
        self.config_name = config_name
        self.cfg = cfg
        self.device = device
        self.paths = paths
        self.meta = dict(meta or {})
        self.val_set = val_set
        self.gen = torch.Generator().manual_seed(cfg.seed)  # hypotheses
        self.loader_gen = torch.Generator().manual_seed(cfg.seed + 1)  # the loader workers' base seeds
        self.loader = DataLoader(train_set, batch_size=cfg.batch_size, sampler=EpochSampler(len(train_set), cfg.seed),
                                 drop_last=True, num_workers=cfg.num_workers,
                                 generator=self.loader_gen)
        # where the next batch starts: the epoch, and the index in that epoch's order
        self.data_epoch, self.data_position = 0, 0
        for module in self.frozen_modules():
            module.requires_grad_(False)
        self.opt = torch.optim.AdamW(param_groups(net, cfg.lr_mults, frozen_prefixes(cfg)), lr=cfg.lr,
                                     weight_decay=cfg.weight_decay)
        self.step = 0
        self.best = -math.inf

    def frozen_modules(self) -> list[torch.nn.Module]:
        net = self.net
        return [getattr(net, m) for m in BINARY_MODULES] if self.cfg.freeze_binary else []

    def _train_mode(self) -> None:
        """Training mode, except frozen modules (their batch-norm statistics stay put)."""
        self.net.train()
        for module in self.frozen_modules():
            module.eval()

    @property
    def criterion(self) -> str:
        """What picks the best checkpoint: val mIoU; val MiD when the binary maps are frozen."""
        return "val_mid" if self.cfg.freeze_binary else "val_miou"

    def score(self, val: dict) -> float:
        """Higher is better."""
        return -val["val_mid"] if self.cfg.freeze_binary else val["val_miou"]

    # -- schedule and losses ----------------------------------------------------------
    def lr_at(self, step: int) -> float:
        c = self.cfg
        warm = min(1.0, (step + 1) / max(c.warmup_steps, 1))
        progress = max(0.0, (step - c.warmup_steps) / max(c.steps - c.warmup_steps, 1))
        cosine = c.final_lr_ratio + (1 - c.final_lr_ratio) * 0.5 * (1 + math.cos(math.pi * min(progress, 1.0)))
        return c.lr * warm * cosine

    def losses(self, batch: dict) -> dict[str, torch.Tensor]:
        c, net = self.cfg, self.net
        mc = net.config
        b = batch["image_prev"].shape[0]
        feats = net.extract(torch.cat((batch["image_prev"], batch["image_latest"])))
        ctx = net.prepare_reference(feats[b:], batch["image_latest"])
        mask = valid_mask(batch)
        if c.freeze_binary:  # nothing the flow heads feed can learn
            out = {"flow": torch.zeros((), device=self.device)}
        else:
            shifts = sample_shifts_px(b, c.shifts_per_pair, mc.max_shift_px, self.gen).to(self.device)
            flow_logits = net.classify_shift(ctx, feats[:b], shifts)
            out = {"flow": masked_bce(flow_logits, shift_labels(batch["flow_px"], shifts), mask[:, None, None])}
        if c.stage == "flow":
            out["loss"] = out["flow"]
            return out
        eta = batch["eta"]
        if c.stage == "binary":
            thr = sample_eta(b, c.thresholds_per_pair, c.train_tau_min_s, c.train_eta_max,
                             mc.frame_dt_s, self.gen)
            at_pixels = round(c.thresholds_per_pair * c.pixel_threshold_share)
            if at_pixels:
                thr[:, :at_pixels] = sample_eta_at_pixels(eta, mask, at_pixels, c.train_tau_min_s,
                                                          c.train_eta_max, mc.frame_dt_s, self.gen)
            thr = thr.to(self.device)
            logits = net.classify_eta(ctx, feats[:b], thr)
            weight = None
            if c.actor_weight != 1.0 or c.inpath_weight != 1.0:
                weight = torch.where(batch["instance"] > 0, c.actor_weight, 1.0)
                if "inpath" in batch:  # the built-in synthetic data has no road, no path
                    weight = torch.where(batch["inpath"], c.inpath_weight, weight)
                weight = weight[:, None]
            labels = eta_labels(eta, thr)
            out["ttc"] = masked_bce(logits, labels, mask[:, None], weight)
            if c.lovasz_weight > 0:
                out["iou"] = lovasz_two_class(logits, labels, mask[:, None])
                out["ttc"] = out["ttc"] + c.lovasz_weight * out["iou"]
            if self.teacher is not None:
                soft = torch.sigmoid(flip_averaged_logits(self.teacher, batch["image_prev"],
                                                          batch["image_latest"], thr))
                out["distill"] = masked_bce(logits, soft, mask[:, None], weight)
                out["ttc"] = out["ttc"] + c.distill_weight * out["distill"]
        else:
            cont = net.continuous(ctx, feats[:b])
            levels = cont.levels.expand(b, -1)
            bce = torch.nn.functional.binary_cross_entropy(
                cont.prob_le.clamp(1e-6, 1 - 1e-6)[mask[:, None].expand_as(cont.prob_le)],
                eta_labels(eta, levels)[mask[:, None].expand_as(cont.prob_le)])
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

    # -- checkpoints --------------------------------------------------------------------
    def _meta(self, val: dict | None = None) -> dict:
        meta = dict(self.meta, stage=self.cfg.stage, step=self.step,
                    frame_dt_s=self.net.config.frame_dt_s, train_config=dataclasses.asdict(self.cfg))
        if val:
            meta.update(val)
        return meta

    def save_last(self) -> None:
        state = {"optimizer": self.opt.state_dict(), "step": self.step, "best": self.best,
                 "stage": self.cfg.stage, "gen": self.gen.get_state(),
                 "loader_gen": self.loader_gen.get_state(), "torch_rng": torch.get_rng_state(),
                 "data_epoch": self.data_epoch, "data_position": self.data_position}
        save_checkpoint(self.paths.last, make_payload(self.net, self.config_name, self._meta(), state))

    def resume(self) -> None:
        # RNG states must stay CPU tensors; the optimizer state follows the parameters
        ckpt = load_checkpoint(self.paths.last, map_location="cpu", expected_config=self.config_name)
        state = ckpt.get("train_state")
        if state is None:
            raise ValueError(f"{self.paths.last} holds no training state")
        self.net.load_state_dict(ckpt["state_dict"])
        if state["stage"] != self.cfg.stage:
            raise ValueError(f"{self.paths.last} is at stage {state['stage']!r}, not {self.cfg.stage!r}")
        # loading replaces each group's settings with the saved ones; keep this run's
        # multipliers (a state saved before lr_mults existed has none)
        mults = [group["lr_mult"] for group in self.opt.param_groups]
        self.opt.load_state_dict(state["optimizer"])
        for group, mult in zip(self.opt.param_groups, mults):
            group["lr_mult"] = mult
        self.step, self.best = int(state["step"]), float(state["best"])
        self.gen.set_state(state["gen"])
        self.loader_gen.set_state(state["loader_gen"])
        torch.set_rng_state(state["torch_rng"])
        if "data_epoch" in state:
            self.data_epoch, self.data_position = int(state["data_epoch"]), int(state["data_position"])
        else:  # saved before the position was: where this step falls in the epochs
            per_epoch = max(len(self.loader), 1)
            self.data_epoch, self.data_position = self.step // per_epoch, self.step % per_epoch * self.cfg.batch_size
        self._trim_log()

    def _trim_log(self) -> None:
        """Drop this stage's log rows after the resumed step: the resumed run logs those steps again."""
        if not self.paths.csv.exists():
            return
        with open(self.paths.csv, newline="") as f:
            rows = list(csv.DictReader(f))
        keep = [r for r in rows if r.get("stage") != self.cfg.stage or int(r["step"]) <= self.step]
        if len(keep) == len(rows):
            return
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=CSV_FIELDS)
        writer.writeheader()
        writer.writerows({k: r.get(k, "") for k in CSV_FIELDS} for r in keep)
        write_text_atomic(self.paths.csv, buf.getvalue())

    # -- loop ---------------------------------------------------------------------------
    def _log(self, row: dict) -> None:
        new = not self.paths.csv.exists()
        with open(self.paths.csv, "a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=CSV_FIELDS)
            if new:
                writer.writeheader()
            writer.writerow({k: row.get(k, "") for k in CSV_FIELDS})

    def run(self) -> dict:
        c = self.cfg
        self._train_mode()
        batches = _forever(self.loader, self.data_epoch, self.data_position)
        bar = tqdm(total=c.steps, initial=self.step, desc=f"train {c.stage}", mininterval=1.0)
        last_val: dict = {}
        # s_per_step: the mean time of the training steps since the last row (loading the
        # batch, forward, backward, update); validation, checkpoints and logging left out
        train_s, timed_steps = 0.0, 0
        while self.step < c.steps:
            t0 = time.perf_counter()
            batch, self.data_epoch, self.data_position = next(batches)
            batch = {k: v.to(self.device, non_blocking=True) for k, v in batch.items()}
            lr = self.lr_at(self.step)
            for group in self.opt.param_groups:
                group["lr"] = lr * group["lr_mult"]
            parts = self.losses(batch)
            self.opt.zero_grad(set_to_none=True)
            parts["loss"].backward()
            grad_norm = float(torch.nn.utils.clip_grad_norm_(
                [q for group in self.opt.param_groups for q in group["params"]], c.clip_grad_norm))
            self.opt.step()
            self.step += 1
            bar.update(1)
            bar.set_postfix(loss=f"{parts['loss'].item():.4f}")
            train_s += time.perf_counter() - t0
            timed_steps += 1
            row = None
            if self.step % c.log_every == 0 or self.step == c.steps:
                dt = train_s / timed_steps
                train_s, timed_steps = 0.0, 0
                row = {"step": self.step, "stage": c.stage, "lr": f"{lr:.3g}", "grad_norm": f"{grad_norm:.4g}",
                       "s_per_step": f"{dt:.3f}", **{f"loss_{k}" if k != "loss" else k: f"{v.item():.5f}"
                                                      for k, v in parts.items()}}
            if self.step % c.val_every == 0 or self.step == c.steps:
                last_val = validate(self.net, self.val_set, stage=c.stage, limit=c.val_limit,
                                    batch_size=c.batch_size, device=self.device)
                self._train_mode()
                row = dict(row or {"step": self.step, "stage": c.stage}, **{k: f"{v:.5f}" for k, v in last_val.items()})
                score = self.score(last_val)
                weights = make_payload(self.net, self.config_name, self._meta(last_val))
                if score > self.best:
                    self.best = score
                    save_checkpoint(self.paths.best, weights)
                if c.keep_checkpoints:
                    save_checkpoint(self.paths.snapshot(c.stage, self.step), weights)
                self.save_last()
            if row is not None:
                self._log(row)
        bar.close()
        best = -self.best if c.freeze_binary else self.best
        return {"stage": c.stage, "steps": self.step, f"best_{self.criterion}": best, **last_val}
