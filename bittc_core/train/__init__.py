"""Training of the Binary-TTC network: ``bittc train``."""

from bittc_core.train.config import STAGES, TrainConfig
from bittc_core.train.loop import RunPaths, Trainer

__all__ = ["STAGES", "TrainConfig", "RunPaths", "Trainer"]
