"""The files of a training run: where they go (``RunPaths``) and the columns of its CSV log."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

# new columns go last, so a run resumed from an older log keeps its columns aligned
CSV_FIELDS = (
    "step",
    "stage",
    "loss",
    "loss_ttc",
    "loss_flow",
    "loss_cont",
    "lr",
    "grad_norm",
    "s_per_step",
    "val_miou",
    "val_mid",
    "loss_iou",
    "loss_distill",
)


@dataclass(frozen=True)
class RunPaths:
    """Files of a run, all beside the best checkpoint ``best`` (the --out path)."""

    best: Path
    last: Path
    csv: Path
    config: Path

    @classmethod
    def from_out(cls, out: str | Path) -> RunPaths:
        out = Path(out)
        stem = out.with_suffix("")
        return cls(
            best=out,
            last=stem.with_name(stem.name + ".last.pt"),
            csv=stem.with_suffix(".csv"),
            config=stem.with_name(stem.name + ".config.yaml"),
        )

    def snapshot(self, stage: str, step: int) -> Path:
        """Where ``keep_checkpoints`` puts the weights of ``stage`` at ``step``."""
        stem = self.best.with_suffix("")
        return stem.with_name(f"{stem.name}.{stage}.step{step:06d}.pt")
