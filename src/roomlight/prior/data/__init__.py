"""Training data of the prior: panorama folders, packed cache, splits, sampling, augmentation.

- :func:`split_files` / :func:`find_panoramas`   which files form the train / val / test splits
- :class:`PanoramaDataset`, :func:`collate_panoramas`   items at the training resolution;
  bad files are reported by name and skipped
- :class:`PackedCache`                           decoded panoramas in one memory-mapped array
- :class:`ResumableBatchSampler`                 seeded batch order that resumes exactly
- :func:`augment_batch` (+ ``roll_azimuth``, ``mirror``, ``tilt``)   the three augmentations
- :func:`dataset_statistics`, :func:`normalization_from_dataset`     ``roomlight data stats``
- :func:`write_toy_dataset`                      instant analytic box rooms for tests and smoke runs

See docs/training.md.
"""

from __future__ import annotations

from roomlight.prior.data.augment import augment_batch, mirror, roll_azimuth, tilt, tilt_rotations
from roomlight.prior.data.cache import PackedCache, default_cache_path
from roomlight.prior.data.dataset import (
    DEPTH_UNITS,
    PanoramaDataset,
    collate_panoramas,
    decode_pair,
    encode_pair,
    load_training_pair,
)
from roomlight.prior.data.sampler import ResumableBatchSampler
from roomlight.prior.data.splits import find_panoramas, has_split_folders, split_files
from roomlight.prior.data.stats import dataset_statistics, normalization_from_dataset
from roomlight.prior.data.toy import toy_panorama, write_toy_dataset

__all__ = [
    "augment_batch", "mirror", "roll_azimuth", "tilt", "tilt_rotations", "PackedCache",
    "default_cache_path", "DEPTH_UNITS", "PanoramaDataset", "collate_panoramas", "decode_pair",
    "encode_pair", "load_training_pair", "ResumableBatchSampler", "find_panoramas",
    "has_split_folders", "split_files", "dataset_statistics", "normalization_from_dataset",
    "toy_panorama", "write_toy_dataset",
]
