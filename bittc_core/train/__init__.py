"""Training of the Binary-TTC network: ``bittc train``."""

from bittc_core.train.config import STAGES, TrainConfig
from bittc_core.train.loop import Trainer
from bittc_core.train.run_files import RunPaths

__all__ = ["STAGES", "TrainConfig", "RunPaths", "Trainer"]
