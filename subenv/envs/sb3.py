"""Stable-Baselines3 on the native vector environment: an SB3 ``VecEnv`` over :class:`DivePlaneVectorEnv`.

SB3 does not take Gymnasium ``VectorEnv`` objects; its own vector API returns ``(obs, rewards,
dones, infos)`` with one ``info`` dict per sub-environment, resets ended sub-environments on the
same step and keeps the last observation of an episode in ``infos[i]["terminal_observation"]``
with ``infos[i]["TimeLimit.truncated"]`` telling truncation from termination (what
``DummyVecEnv`` does). :class:`SB3VecEnv` gives exactly that over any Gymnasium ``VectorEnv``
in ``SAME_STEP`` autoreset mode, so SB3 trains on :class:`~subenv.envs.DivePlaneVectorEnv`
without a Python loop over sub-environments::

    from stable_baselines3 import PPO
    from subenv.envs.sb3 import make_sb3_vec_env

    venv = make_sb3_vec_env("subenv/DivePlane-v0", n_envs=64, seed=0)
    PPO("MlpPolicy", venv).learn(100_000)

Needs the ``rl`` extra (``pip install "subenv[rl]"``); ``import subenv`` never imports this module.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

from subenv.extras import MissingExtra, missing_extra_message

try:
    from stable_baselines3.common.vec_env.base_vec_env import (
        VecEnv,
        VecEnvIndices,
        VecEnvObs,
        VecEnvStepReturn,
    )
except ImportError as error:  # pragma: no cover - depends on the installation
    raise MissingExtra(missing_extra_message("rl", "subenv.envs.sb3"), name="stable_baselines3") from error

__all__ = ["SB3VecEnv", "make_sb3_vec_env"]

_FINAL_KEYS = frozenset({"final_obs", "final_info"})


class SB3VecEnv(VecEnv):
    """A Stable-Baselines3 ``VecEnv`` over a Gymnasium ``VectorEnv`` that autoresets on the same step.

    Parameters
    ----------
    venv : gymnasium.vector.VectorEnv
        With ``metadata["autoreset_mode"] == AutoresetMode.SAME_STEP`` (for subenv:
        ``gym.make_vec(id, num_envs=n, autoreset_mode="SameStep")``; :func:`make_sb3_vec_env`
        does this).
    info_keys : iterable of str, optional
        The keys of the environment's ``info`` copied into SB3's per-environment dicts; None
        (default) copies all of them, as ``DummyVecEnv`` does. Building thousands of dicts per
        step costs more than stepping the environments, so pass ``()`` when training does not
        read them. ``"terminal_observation"`` and ``"TimeLimit.truncated"`` are always set.
    """

    def __init__(self, venv: gym.vector.VectorEnv, info_keys: Iterable[str] | None = None) -> None:
        mode = venv.metadata.get("autoreset_mode")
        if mode != AutoresetMode.SAME_STEP:
            raise ValueError(
                f"the vector env autoresets with {mode!r}: SB3VecEnv needs AutoresetMode.SAME_STEP "
                "(make it with autoreset_mode='SameStep')"
            )
        self.venv = venv
        self.info_keys = None if info_keys is None else tuple(info_keys)
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    # --- SB3 VecEnv API -------------------------------------------------------------------------
    def reset(self) -> VecEnvObs:
        """Reset every sub-environment with the seeds and options set since the last reset (SB3's
        ``seed`` and ``set_options``), in one vector reset per distinct options dict.

        Returns the observations, shape (num_envs, obs_dim); each sub-environment's ``info`` goes to
        ``reset_infos``.
        """
        seeds = list(self._seeds)
        options = [dict(o) for o in self._options]
        groups: dict[str, list[int]] = {}
        for i, o in enumerate(options):
            groups.setdefault(repr(sorted(o.items())), []).append(i)
        obs = None
        for indices in groups.values():  # one reset per distinct options dict
            opts = dict(options[indices[0]])
            if len(groups) > 1:
                mask = np.zeros(self.num_envs, dtype=bool)
                mask[indices] = True
                opts["reset_mask"] = mask
            seed = None if all(s is None for s in seeds) else seeds
            obs, infos = self.venv.reset(seed=seed, options=opts or None)  # type: ignore[arg-type]
            for i, info in zip(indices, self._split(infos, indices), strict=True):
                self.reset_infos[i] = info
        self._reset_seeds()
        self._reset_options()
        return cast(VecEnvObs, obs)

    def step_async(self, actions: np.ndarray) -> None:
        """Keep ``actions``, shape (num_envs, action_dim), for :meth:`step_wait`."""
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        """Step every sub-environment with the actions of :meth:`step_async`: SB3's ``(obs, rewards,
        dones, infos)``, the ended sub-environments already reset (``obs`` their first observation),
        with their last observation in ``infos[i]["terminal_observation"]`` and
        ``infos[i]["TimeLimit.truncated"]`` set for every one."""
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        dones = terminated | truncated
        ended = np.flatnonzero(dones)
        step_infos = self._split(infos, range(self.num_envs))
        if len(ended):
            final_infos = self._split(infos["final_info"], ended)
            for i, final in zip(ended, final_infos, strict=True):
                self.reset_infos[i] = step_infos[i]  # the reset's info, as DummyVecEnv keeps it
                final["terminal_observation"] = infos["final_obs"][i]
                step_infos[i] = final
        for info, term, trunc in zip(step_infos, terminated.tolist(), truncated.tolist(), strict=True):
            info["TimeLimit.truncated"] = trunc and not term
        return obs, rewards.astype(np.float32), dones, step_infos

    def close(self) -> None:
        """Close the vector env."""
        self.venv.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """An attribute of the vector env (or of its ``config``), the same for every index."""
        target = self.venv if hasattr(self.venv, attr_name) else getattr(self.venv, "config", None)
        if target is None or not hasattr(target, attr_name):
            raise AttributeError(f"{type(self.venv).__name__} has no attribute {attr_name!r}")
        value = getattr(target, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Not supported (NotImplementedError): the sub-environments share one configuration."""
        raise NotImplementedError(
            f"set_attr({attr_name!r}): the sub-environments of a native vector env share one configuration"
        )

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Call a method of the vector env itself, once, for all sub-environments together.

        The sub-environments of a native vector env are rows of one table, not objects, so only
        methods of the vector env that act on all of them (for subenv: ``set_scenario``) can be
        called, and only with every index.
        """
        chosen = list(self._get_indices(indices))
        method = getattr(self.venv, method_name, None)
        if method is None or not callable(method) or method_name.startswith("_"):
            raise AttributeError(f"{type(self.venv).__name__} has no public method {method_name!r}")
        if sorted(chosen) != list(range(self.num_envs)):
            raise NotImplementedError(
                f"env_method({method_name!r}, indices={indices!r}): the sub-environments of a native vector "
                "env share one configuration; call it for all of them (indices=None)"
            )
        result = method(*method_args, **method_kwargs)
        return [result for _ in chosen]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """False for every index: the sub-environments are rows of one table, never wrapped."""
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        """The frames the vector env renders (the first sub-environment's for subenv)."""
        frames = self.venv.render()
        return list(cast(Sequence[np.ndarray], frames)) if frames is not None else []

    # --- helpers --------------------------------------------------------------------------------
    def _split(self, infos: dict[str, Any], indices: Iterable[int]) -> list[dict[str, Any]]:
        """Gymnasium's dict of arrays -> one dict per index (the keys each sub-environment reported)."""
        indices = list(indices)
        keys = [k for k in infos if not k.startswith("_") and k not in _FINAL_KEYS]
        if self.info_keys is not None:
            keys = [k for k in keys if k in self.info_keys]
        out: list[dict[str, Any]] = [{} for _ in indices]
        for key in keys:
            values, mask = infos[key], infos.get("_" + key)
            if isinstance(values, dict):
                for d, sub in zip(out, self._split(values, indices), strict=True):
                    d[key] = sub
                continue
            picked = (
                values[indices].tolist() if isinstance(values, np.ndarray) else [values[i] for i in indices]
            )
            present = mask[indices].tolist() if mask is not None else [True] * len(indices)
            for d, value, ok in zip(out, picked, present, strict=True):
                if ok:
                    d[key] = value
        return out


def make_sb3_vec_env(
    env_id: str = "subenv/DivePlane-v0",
    n_envs: int = 1,
    seed: int | None = None,
    info_keys: Iterable[str] | None = None,
    **kwargs: Any,
) -> SB3VecEnv:
    """``gym.make_vec(env_id, num_envs=n_envs, autoreset_mode="SameStep", **kwargs)`` for SB3.

    ``seed`` seeds the first reset (sub-environment ``i`` with ``seed + i``, as SB3's
    ``make_vec_env`` does); ``info_keys`` as in :class:`SB3VecEnv`.
    """
    venv = gym.make_vec(env_id, num_envs=n_envs, autoreset_mode=AutoresetMode.SAME_STEP, **kwargs)
    sb3_env = SB3VecEnv(venv, info_keys=info_keys)
    if seed is not None:
        sb3_env.seed(seed)
    return sb3_env
