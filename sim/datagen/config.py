"""What a generated dataset shares (``GenerationConfig``, stored as DIR/generation.yaml),
its seeds and the generator's tuning constants.

Seeds: sample ``index`` of ``split`` has the sample seed ``SPLIT_SEED_BASE[split] +
index`` (disjoint ranges per split); its scene is drawn from ``SeedSequence([dataset
seed, sample seed])``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bittc_core.errors import ConfigError

SPLIT_SEED_BASE = {"train": 0, "val": 1_000_000_000, "test": 2_000_000_000}
MAX_SAMPLES_PER_SPLIT = 1_000_000_000
BACKENDS = ("local", "ray")  # a process pool or Ray tasks
MAX_ATTEMPTS = 3  # tries per sample before the run fails
# a sample allocates ~10^5 short-lived Python objects (mesh lists, traffic, JSON): with
# the default thresholds the cyclic GC runs often and walks every long-lived object of a
# worker (modules, the world); freezing those and collecting less often saves ~3 ms
GC_THRESHOLDS = (20_000, 50, 100)
LOCAL_CHUNK = 4  # samples per task sent to a local worker process
RAY_CHUNK = 8  # samples per Ray task
# the run statistics' steady_samples_per_s is measured over at least this many completions
# (and at least one more chunk per worker) spanning at least this long; else it is None
STEADY_MIN_SAMPLES = 20
STEADY_MIN_S = 2.0  # [s]


@dataclass(frozen=True)
class GenerationConfig:
    """What every split of one dataset shares (stored as DIR/generation.yaml)."""

    seed: int = 0
    height_px: int = 96
    width_px: int = 288
    fps_hz: float = 10.0  # [Hz]
    clip_length: int = 2  # frames per sample
    supersample: int = 1  # render at this factor and average down
    ground_texture: str = "detailed"  # sim.textures.GROUND_STYLES; "smooth" = bittc_v1's ground
    vehicle_texture: str = "plain"  # sim.textures.VEHICLE_STYLES; "detailed" = bittc_v3's vehicles
    ahead_share: float = 0.0  # share of samples with a braking case ahead (sim.random_scene.AHEAD_*)
    fovea_share: float = 0.0  # share of samples seen through a fovea (sim.fovea_scene)
    realism_share: float = 0.0  # share of samples through a sensor drawn per clip (sim.sensor)
    realism_codecs: str = "jpeg+video"  # the compressions a sensor draws from (sim.sensor.CODEC_SETS)
    vru_share: float = 0.0  # share of samples with pedestrians and cyclists (sim.random_vrus)

    def __post_init__(self) -> None:
        if self.seed < 0:
            raise ConfigError(f"seed {self.seed}: must be >= 0")
        if not 2 <= self.clip_length <= 32:
            raise ConfigError(f"clip_length {self.clip_length}: must be in [2, 32]")
        if not 1.0 <= self.fps_hz <= 100.0:
            raise ConfigError(f"fps_hz {self.fps_hz}: must be in [1, 100] Hz")
        if not 0.0 <= self.ahead_share <= 1.0:
            raise ConfigError(f"ahead_share {self.ahead_share}: must be in [0, 1]")
        if not 0.0 <= self.fovea_share <= 1.0:
            raise ConfigError(f"fovea_share {self.fovea_share}: must be in [0, 1]")
        if not 0.0 <= self.realism_share <= 1.0:
            raise ConfigError(f"realism_share {self.realism_share}: must be in [0, 1]")
        from sim.sensor import CODEC_SETS

        if self.realism_codecs not in CODEC_SETS:
            raise ConfigError(f"realism_codecs {self.realism_codecs!r}: must be one of {', '.join(CODEC_SETS)}")
        if not 0.0 <= self.vru_share <= 1.0:
            raise ConfigError(f"vru_share {self.vru_share}: must be in [0, 1]")
        if self.supersample not in (1, 2, 3, 4):
            raise ConfigError(f"supersample {self.supersample}: must be 1, 2, 3 or 4")
        from sim.textures import GROUND_STYLES, VEHICLE_STYLES

        if self.ground_texture not in GROUND_STYLES:
            raise ConfigError(f"ground_texture {self.ground_texture!r}: must be one of {', '.join(GROUND_STYLES)}")
        if self.vehicle_texture not in VEHICLE_STYLES:
            raise ConfigError(f"vehicle_texture {self.vehicle_texture!r}: must be one of {', '.join(VEHICLE_STYLES)}")


def sample_seed(split: str, index: int) -> int:
    return SPLIT_SEED_BASE[split] + index


def scene_seed(cfg: GenerationConfig, split: str, index: int) -> int:
    return int(np.random.SeedSequence([cfg.seed, sample_seed(split, index)]).generate_state(1, np.uint64)[0] % (2**63))
