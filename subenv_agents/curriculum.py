"""A training curriculum placed by the physics: speed stages relative to the critical speed.

Below the critical speed u_cr (Riedel 1993 eq. 3.9) level flight is unstable and the planes
reverse; near it they have almost no net effect on depth. An agent that starts there sees
mostly failures. The curriculum starts at speeds well above u_cr (the planes work as expected)
and widens the speed range stage by stage down through u_cr, with the stage bands placed by
:func:`subenv.analysis.speed_curriculum` in units of each episode's own critical speed. The
ballast offset x_GB and the excess buoyancy grow with the stages too. After the last stage the
environment's own scenario (for ``subenv/DivePlane-v0``: ``Randomized``) takes over.

A stage advances when the success rate of its last ``window`` episodes reaches ``threshold``.
An episode succeeds as :func:`subenv.evaluation.metrics.episode_success` decides: it ran to its
time limit (not terminated) and |depth error| stayed within
:data:`~subenv.evaluation.metrics.DEPTH_TOLERANCE_M` over the final
:data:`~subenv.evaluation.metrics.HOLD_WINDOW_S`.

:class:`CurriculumSchedule` is the bookkeeping (no Stable-Baselines3); :class:`CurriculumCallback`
drives it from a training run and moves the environment with ``set_scenario``.
"""

from __future__ import annotations

import json
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from tqdm import tqdm

from subenv.analysis.curriculum import DEFAULT_STAGES, speed_curriculum
from subenv.evaluation.metrics import DEPTH_TOLERANCE_M, episode_success
from subenv.evaluation.results import atomic_write_text
from subenv.scenarios import Scenario
from subenv.vehicles import Vehicle
from subenv_agents.config import CurriculumConfig

__all__ = ["CurriculumCallback", "CurriculumSchedule", "stage_scenarios"]

STATE_FILE = "curriculum.json"
"""Written into the run folder at every advance, so a resumed run continues at its stage."""


def stage_scenarios(
    base: Scenario, config: CurriculumConfig, vehicle: Vehicle, alpha: float = 0.0
) -> list[Scenario]:
    """The scenarios of the stages, then ``base`` (the environment's own scenario) as the last one.

    Stage k draws u / u_cr uniformly from [low_k, high_0] (its own band and every easier one, so
    earlier skills stay in practice), |x_GB| up to k / (K - 1) of ``config.max_x_GB_m`` with a
    random sign, and (B - W) / W up to the same fraction of ``config.max_excess_buoyancy_fraction``.
    Depth commands, initial offsets and pitches are those of the base scenarios (8-15 m, +-2 m,
    +-0.05 rad); ``base``'s randomisation (z_GB scale, C_D, sensor noise, disturbance) applies
    from the first stage on.
    """
    stages = speed_curriculum(vehicle, alpha, config.stages if config.stages is not None else DEFAULT_STAGES)
    top = stages[0].ratio_high
    out = []
    for k, stage in enumerate(stages):
        fraction = k / (len(stages) - 1) if len(stages) > 1 else 1.0
        out.append(
            Scenario(
                name="Curriculum" + "".join(part.capitalize() for part in stage.name.split("_")),
                description=f"Curriculum stage {k + 1}/{len(stages)} ({stage.name}): u/u_cr in "
                f"[{stage.ratio_low:g}, {top:g}]",
                speed_ratio=(stage.ratio_low, top),
                depth_command_m=(8.0, 15.0),
                initial_depth_offset_m=(-2.0, 2.0),
                initial_pitch_rad=(-0.05, 0.05),
                z_GB_scale=base.z_GB_scale,
                x_GB_m=(0.0, fraction * config.max_x_GB_m),
                x_GB_sign_random=True,
                excess_buoyancy_fraction=(0.0, fraction * config.max_excess_buoyancy_fraction),
                crossflow_drag=base.crossflow_drag,
                sensor_noise=base.sensor_noise,
                disturbance_std_N=base.disturbance_std_N,
                duration_s=600.0,
            )
        )
    out.append(base)
    return out


class CurriculumSchedule:
    """Which stage training is at, from a stream of episode outcomes.

    Parameters
    ----------
    n_stages : int
        Number of stages, the environment's own scenario included (the last one, never left).
    threshold, window
        Advance when ``window`` episodes of the current stage have been recorded and at least
        ``threshold`` of the last ``window`` succeeded.
    stage : int
        The stage to start at (a resumed run's).
    """

    def __init__(self, n_stages: int, threshold: float, window: int, stage: int = 0) -> None:
        if not (isinstance(n_stages, int) and n_stages >= 1):
            raise ValueError(f"n_stages={n_stages!r} is invalid: must be an integer >= 1")
        if not (0 <= stage < n_stages):
            raise ValueError(f"stage={stage!r} is invalid: must be in [0, {n_stages - 1}]")
        self.n_stages = n_stages
        self.threshold = threshold
        self.window = window
        self.stage = stage
        self._outcomes: deque[bool] = deque(maxlen=window)

    @property
    def final(self) -> bool:
        """At the last stage (the environment's own scenario)."""
        return self.stage == self.n_stages - 1

    @property
    def success_rate(self) -> float:
        """Success rate of the current stage's recorded episodes (nan before the first)."""
        return float(np.mean(self._outcomes)) if self._outcomes else float("nan")

    def record(self, success: bool) -> bool:
        """Record one episode of the current stage; True if this advanced the stage."""
        self._outcomes.append(bool(success))
        if self.final or len(self._outcomes) < self.window or self.success_rate < self.threshold:
            return False
        self.stage += 1
        self._outcomes.clear()
        return True


class CurriculumCallback(BaseCallback):
    """Moves a training environment through :func:`stage_scenarios` as its episodes succeed.

    The training environment must offer ``set_scenario`` through ``env_method`` (the
    :class:`~subenv.envs.sb3.SB3VecEnv` over :class:`~subenv.envs.DivePlaneVectorEnv` does) and
    report ``time_s``, ``depth_error_m`` in its infos. Only episodes that started after the
    current stage began count towards it. Logs ``curriculum/stage`` and
    ``curriculum/success_rate``; writes :data:`STATE_FILE` into ``state_dir`` at every advance.
    """

    def __init__(
        self,
        scenarios: list[Scenario],
        config: CurriculumConfig,
        state_dir: str | Path | None = None,
        stage: int = 0,
        verbose: int = 0,
    ) -> None:
        super().__init__(verbose)
        self.scenarios = scenarios
        self.schedule = CurriculumSchedule(len(scenarios), config.threshold, config.window, stage)
        self.start_stage = stage
        self.state_dir = Path(state_dir) if state_dir is not None else None
        self.advances: list[tuple[int, int]] = []
        """(timestep, new stage) of every advance."""
        self._episode_stage = np.zeros(0, dtype=int)
        self._last_violation_s = np.zeros(0)

    def _on_training_start(self) -> None:
        n = self.training_env.num_envs
        # Episodes already under way were drawn before the curriculum: they count for no stage.
        self._episode_stage = np.full(n, -1)
        self._last_violation_s = np.full(n, -np.inf)
        self.training_env.env_method("set_scenario", self.scenarios[self.schedule.stage])

    def _on_step(self) -> bool:
        infos: list[dict[str, Any]] = self.locals["infos"]
        dones: np.ndarray = self.locals["dones"]
        errors = np.array([info["depth_error_m"] for info in infos])
        times = np.array([info["time_s"] for info in infos])
        outside = ~(np.abs(errors) <= DEPTH_TOLERANCE_M)  # as in episode_metrics: a nan error is outside
        self._last_violation_s[outside] = times[outside]
        # Sub-environments autoreset on the step that ends an episode, before this callback runs:
        # their new episodes were drawn from the scenario of the stage before any advance below.
        drawn_stage = self.schedule.stage
        for i in np.flatnonzero(dones):
            info = infos[i]
            if self._episode_stage[i] == self.schedule.stage:
                # Episodes start at time 0. Their reset sample, not seen here, lies in the hold
                # window only for an episode no longer than the window (the stages last 600 s).
                terminated = not info.get("TimeLimit.truncated", False) or bool(
                    info.get("termination_reason")
                )
                success = episode_success(
                    terminated=terminated,
                    start_s=0.0,
                    end_s=float(times[i]),
                    last_outside_s=float(self._last_violation_s[i]),
                )
                if self.schedule.record(success):
                    self._advance()
            self._episode_stage[i] = drawn_stage
            self._last_violation_s[i] = -np.inf
        self.logger.record("curriculum/stage", self.schedule.stage)
        rate = self.schedule.success_rate
        if rate == rate:
            self.logger.record("curriculum/success_rate", rate)
        return True

    def _advance(self) -> None:
        stage = self.schedule.stage
        self.training_env.env_method("set_scenario", self.scenarios[stage])
        self.advances.append((self.num_timesteps, stage))
        if self.verbose:
            tqdm.write(
                f"curriculum: stage {stage} ({self.scenarios[stage].name}) at {self.num_timesteps} steps"
            )
        if self.state_dir is not None:
            write_state(self.state_dir, stage, self.advances, self.start_stage)


def write_state(state_dir: Path, stage: int, advances: list[tuple[int, int]], start_stage: int = 0) -> None:
    """Write :data:`STATE_FILE` completely or not at all: the stage now, the stage the run started at
    and the (timestep, new stage) of every advance since."""
    state_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(
        state_dir / STATE_FILE,
        json.dumps({"stage": stage, "start_stage": start_stage, "advances": advances}) + "\n",
    )


def read_stage(state_dir: Path, timestep: int | None = None) -> int:
    """The stage recorded in ``state_dir`` (0 if none was); with ``timestep``, the stage training was at
    after that many steps (a checkpoint's or a selected policy's, not the run's last)."""
    path = Path(state_dir) / STATE_FILE
    if not path.exists():
        return 0
    state = json.loads(path.read_text())
    if timestep is None:
        return int(state["stage"])
    stage = state.get("start_stage")
    if stage is None:  # written before start stages were: a run that advanced started at 0
        stage = 0 if state["advances"] else state["stage"]
    for step, new_stage in state["advances"]:
        if step <= timestep:
            stage = new_stage
    return int(stage)
