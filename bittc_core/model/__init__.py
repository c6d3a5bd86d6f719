"""The Binary-TTC network (Badki et al., CVPR 2021), written from the paper."""

from bittc_core.model.config import CONFIGS, ModelConfig, get_config
from bittc_core.model.network import BinaryTTCNet, ContinuousOutput, ReferenceContext, count_parameters

__all__ = [
    "CONFIGS",
    "ModelConfig",
    "get_config",
    "BinaryTTCNet",
    "ContinuousOutput",
    "ReferenceContext",
    "count_parameters",
]
