"""A resumable, seeded stream of training batches.

The order of the data is a pure function of (seed, batch number): epoch e visits the items in
the permutation ``randperm(n)`` drawn from a generator seeded with (seed, e), in consecutive
batches of the *global* batch size (the last incomplete batch of an epoch is dropped). So a run
that restarts at batch k continues with exactly the batches an uninterrupted run would have
drawn, without saving any sampler state beyond k. Under DDP, rank r of w takes every w-th item
of each global batch, so the union over ranks is the same global batch for any w.
"""

from __future__ import annotations

import torch

from roomlight.errors import RoomlightError

__all__ = ["ResumableBatchSampler"]


class ResumableBatchSampler:
    """Infinite iterator of index lists for ``torch.utils.data.DataLoader(batch_sampler=...)``.

    Args:
        n: number of items in the dataset.
        batch_size: global batch size B (over all ranks); must be <= n.
        seed: base seed of the permutations.
        start: batch number to start from (batches already consumed, for resuming).
        rank, world_size: this process's share of each global batch (DDP).
        shuffle: permute each epoch (False: items in order, for evaluation).
    """

    def __init__(self, n: int, batch_size: int, seed: int = 0, start: int = 0, rank: int = 0,
                 world_size: int = 1, shuffle: bool = True):
        if n <= 0:
            raise RoomlightError("ResumableBatchSampler: the dataset is empty")
        if not 0 < batch_size <= n:
            raise RoomlightError(
                f"batch size {batch_size} must be between 1 and the number of training panoramas ({n}); "
                "lower --batch-size or add data"
            )
        if batch_size % world_size:
            raise RoomlightError(f"batch size {batch_size} is not divisible by the number of processes {world_size}")
        self.n, self.batch_size, self.seed = n, batch_size, seed
        self.start, self.rank, self.world_size, self.shuffle = start, rank, world_size, shuffle
        self._perm_epoch, self._perm = -1, None

    @property
    def batches_per_epoch(self) -> int:
        """Complete global batches per pass over the data (floor(n / B))."""
        return self.n // self.batch_size

    def permutation(self, epoch: int) -> torch.Tensor:
        """(n,) int64 order of the items in ``epoch``."""
        if epoch != self._perm_epoch:
            if self.shuffle:
                g = torch.Generator().manual_seed(int(self.seed) * 1_000_003 + int(epoch))
                self._perm = torch.randperm(self.n, generator=g)
            else:
                self._perm = torch.arange(self.n)
            self._perm_epoch = epoch
        return self._perm

    def batch(self, k: int) -> list[int]:
        """Indices of global batch ``k`` (counting from 0 at the start of training) for this rank."""
        epoch, pos = divmod(k, self.batches_per_epoch)
        perm = self.permutation(epoch)
        b = perm[pos * self.batch_size:(pos + 1) * self.batch_size]
        return b[self.rank::self.world_size].tolist()

    def epoch_of(self, k: int) -> int:
        """Epoch (from 0) that global batch ``k`` belongs to."""
        return k // self.batches_per_epoch

    def __iter__(self):
        k = self.start
        while True:
            yield self.batch(k)
            k += 1
