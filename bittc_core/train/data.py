"""Where training and evaluation pairs come from.

``--data synthetic`` selects the generator of ``bittc_core.data.synthetic`` (fixed,
seed-independent val and test splits); any other value is a dataset folder read by
``bittc_core.data.dataset.TTCDataset(root, split, augment, seed)``.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from torch.utils.data import Dataset

from bittc_core.data.synthetic import SyntheticPairs
from bittc_core.errors import ConfigError

SYNTHETIC = "synthetic"
SPLITS = ("train", "val", "test")
SYNTHETIC_SPLITS = {"train": (100_000, 0), "val": (256, 1_000_003), "test": (256, 2_000_003)}


def open_split(data: str, split: str, *, augment: bool = False, seed: int = 0) -> Dataset:
    if split not in SPLITS:
        raise ConfigError(f"split {split!r}: expected one of {SPLITS}")
    if data == SYNTHETIC:
        length, split_seed = SYNTHETIC_SPLITS[split]
        return SyntheticPairs(length, seed=split_seed + (seed if split == "train" else 0))
    root = Path(data)
    if not root.is_dir():
        raise ConfigError(f"dataset {data!r}: not a directory (or {SYNTHETIC!r})")
    try:
        module = importlib.import_module("bittc_core.data.dataset")
    except ImportError as err:
        raise ConfigError(
            f"cannot read {data!r}: the dataset loader bittc_core.data.dataset is not available ({err})"
        ) from None
    try:
        return module.TTCDataset(root, split, augment=augment, seed=seed)
    except (OSError, ValueError) as err:
        raise ConfigError(f"cannot open split {split!r} of {data!r}: {err}") from None
