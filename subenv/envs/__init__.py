"""The Gymnasium environments."""

from subenv.envs.config import DivePlaneConfig
from subenv.envs.dive_plane import OBSERVATION_NAMES, DivePlaneEnv
from subenv.envs.registration import HEADLINE_ID, env_ids, register_env, register_envs
from subenv.envs.validity import FreeSurfaceRangeWarning
from subenv.envs.vector import DivePlaneVectorEnv

__all__ = [
    "HEADLINE_ID",
    "OBSERVATION_NAMES",
    "DivePlaneConfig",
    "DivePlaneEnv",
    "DivePlaneVectorEnv",
    "FreeSurfaceRangeWarning",
    "env_ids",
    "register_env",
    "register_envs",
]
