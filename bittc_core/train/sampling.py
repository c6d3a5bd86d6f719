"""The training order: a per-epoch permutation that a resumed run continues where it stopped."""

from __future__ import annotations

import numpy as np
import torch
from torch.utils.data import DataLoader, Sampler


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
        return iter(self.order(self.epoch)[self.start :].tolist())

    def __len__(self) -> int:
        return self.n


def forever(loader: DataLoader, epoch: int = 0, position: int = 0):
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
