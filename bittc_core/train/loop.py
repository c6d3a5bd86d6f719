"""The training loop of one stage (paper Sec. 4.4 and Supp. B).

Stages: ``flow``: binary-flow pre-training, TTC head unsupervised; ``binary``: binary
TTC (several eta thresholds per pair, vehicle (actor) pixels, moving or not, weighted
``actor_weight``; BCE,
plus ``lovasz_weight`` x a Lovasz surrogate of the per-map two-class IoU, plus
``distill_weight`` x BCE towards a frozen teacher's flip-averaged maps, actor pixels
weighted alike; with ``distill_scope`` "scenery" or "scenery-vehicles" the teacher's maps
replace the labels on those pixels instead) + binary flow
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

import torch
from torch.utils.data import DataLoader, Dataset
from tqdm import tqdm

from bittc_core.atomic import write_text_atomic
from bittc_core.checkpoint import load_checkpoint, make_payload, save_checkpoint
from bittc_core.model import BinaryTTCNet
from bittc_core.train.config import TrainConfig
from bittc_core.train.losses_stage import stage_losses
from bittc_core.train.params import BINARY_MODULES, frozen_prefixes, param_groups
from bittc_core.train.run_files import CSV_FIELDS, RunPaths
from bittc_core.train.sampling import EpochSampler, forever
from bittc_core.train.validate import validate


class Trainer:
    def __init__(
        self,
        net: BinaryTTCNet,
        config_name: str,
        cfg: TrainConfig,
        train_set: Dataset,
        val_set: Dataset,
        device: torch.device,
        paths: RunPaths,
        meta: dict | None = None,
        teacher: BinaryTTCNet | None = None,
    ) -> None:
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
        self.loader = DataLoader(
            train_set,
            batch_size=cfg.batch_size,
            sampler=EpochSampler(len(train_set), cfg.seed),
            drop_last=True,
            num_workers=cfg.num_workers,
            generator=self.loader_gen,
        )
        # where the next batch starts: the epoch, and the index in that epoch's order
        self.data_epoch, self.data_position = 0, 0
        for module in self.frozen_modules():
            module.requires_grad_(False)
        self.opt = torch.optim.AdamW(
            param_groups(net, cfg.lr_mults, frozen_prefixes(cfg)), lr=cfg.lr, weight_decay=cfg.weight_decay
        )
        self.step = 0
        self.best = -math.inf

    def frozen_modules(self) -> list[torch.nn.Module]:
        net = self.net
        return [getattr(net, m) for m in BINARY_MODULES] if self.cfg.freeze_binary else []

    def _train_mode(self) -> None:
        """Training mode, except frozen modules (their batch-norm statistics stay put) and,
        with ``freeze_norm_stats``, every batch norm (normalising by its running statistics,
        which stay put; its scale and shift still learn)."""
        self.net.train()
        for module in self.frozen_modules():
            module.eval()
        if self.cfg.freeze_norm_stats:
            for module in self.net.modules():
                if isinstance(module, torch.nn.modules.batchnorm._BatchNorm):
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
        return stage_losses(self.net, self.cfg, batch, self.gen, self.device, self.teacher)

    # -- checkpoints --------------------------------------------------------------------
    def _meta(self, val: dict | None = None) -> dict:
        meta = dict(
            self.meta,
            stage=self.cfg.stage,
            step=self.step,
            frame_dt_s=self.net.config.frame_dt_s,
            train_config=dataclasses.asdict(self.cfg),
        )
        if val:
            meta.update(val)
        return meta

    def save_last(self) -> None:
        state = {
            "optimizer": self.opt.state_dict(),
            "step": self.step,
            "best": self.best,
            "stage": self.cfg.stage,
            "gen": self.gen.get_state(),
            "loader_gen": self.loader_gen.get_state(),
            "torch_rng": torch.get_rng_state(),
            "data_epoch": self.data_epoch,
            "data_position": self.data_position,
        }
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
        batches = forever(self.loader, self.data_epoch, self.data_position)
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
            grad_norm = float(
                torch.nn.utils.clip_grad_norm_(
                    [q for group in self.opt.param_groups for q in group["params"]], c.clip_grad_norm
                )
            )
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
                row = {
                    "step": self.step,
                    "stage": c.stage,
                    "lr": f"{lr:.3g}",
                    "grad_norm": f"{grad_norm:.4g}",
                    "s_per_step": f"{dt:.3f}",
                    **{f"loss_{k}" if k != "loss" else k: f"{v.item():.5f}" for k, v in parts.items()},
                }
            if self.step % c.val_every == 0 or self.step == c.steps:
                last_val = validate(
                    self.net,
                    self.val_set,
                    stage=c.stage,
                    limit=c.val_limit,
                    batch_size=c.batch_size,
                    device=self.device,
                )
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
