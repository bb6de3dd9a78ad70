"""Model selection on validation episodes: keep the policy that succeeds most, with the least plane effort.

Training curves on these environments are not monotonic: a policy that holds depth below the
critical speed at one point of training can lose it a million steps later (it finds the pitched
branch again, or stops bothering with the weak low-speed planes). Instead of shipping whatever
the last update left, :class:`SelectionCallback` evaluates the current deterministic policy
every ``freq`` steps, and once more at the end, with the harness of ``subenv evaluate`` on
validation episodes, and keeps the best one in ``<run>/selected/`` (``model.zip``,
``vecnormalize.pkl``, ``config.yml``: a folder :func:`subenv_agents.load_agent` reads).

"Best" is the target of the shipped agents: the highest success rate over the
:data:`SELECTION_SCENARIOS` (the low-speed, near-critical and speed-transient episodes), ties
broken by the lower plane RMS. The validation episodes use the seeds :data:`VALIDATION_SEED`
+ i: never those of the evaluation suites (``subenv.evaluation.DEFAULT_SEED`` = 10000 + i), on
which the selected model is then reported, so the reported numbers are not selected on.
The selection's cost is part of the training run's wall time.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback
from tqdm import tqdm

from subenv.evaluation.results import atomic_output_dir, atomic_write_bytes, atomic_write_text
from subenv_agents.config import AgentConfig
from subenv_agents.policy import (
    CONFIG_FILE,
    MODEL_FILE,
    SELECTED_DIR,
    VECNORMALIZE_FILE,
    TrainedAgent,
    save_model,
    save_statistics,
)
from subenv_agents.records import REVERSAL_SCENARIOS

__all__ = ["SELECTED_DIR", "SELECTION_SCENARIOS", "VALIDATION_SEED", "SelectionCallback", "validation_score"]

SELECTION_SCENARIOS: Final = REVERSAL_SCENARIOS
"""Where the shipped agents' target is measured (:mod:`subenv_agents.records`), and so where they are
selected."""
VALIDATION_SEED: Final = 50_000
"""Validation episode i is ``reset(seed=VALIDATION_SEED + i)``: disjoint from the evaluation suites' seeds."""
SELECTION_FILE: Final = "selection.json"


def validation_score(
    agent: TrainedAgent, scenarios: Sequence[str], episodes: int, seed: int = VALIDATION_SEED
) -> dict[str, float]:
    """Success rate (mean over ``scenarios``) and mean plane RMS [rad] of ``agent``'s deterministic
    policy on ``episodes`` validation episodes per scenario."""
    from subenv.evaluation import evaluate
    from subenv_agents.controller import AgentController

    results = evaluate(
        [AgentController(agent, name="candidate")],
        list(scenarios),
        episodes=episodes,
        seed=seed,
        progress=False,
        keep_trajectories=0,
    )
    return {
        "success_rate": float(np.mean([r.metrics.success for r in results])),
        "plane_rms_rad": float(np.mean([r.metrics.plane_rms_rad for r in results])),
    }


class SelectionCallback(BaseCallback):
    """Evaluate the policy every ``freq`` environment steps and at the end; keep the best in
    ``<run>/selected/``.

    Parameters
    ----------
    config : AgentConfig
        The run's config (written beside the selected model, so that it loads on its own).
    run_dir : path
        The run folder.
    freq : int
        Environment steps between evaluations (> 0).
    episodes : int
        Validation episodes per scenario.
    scenarios : sequence of str
        Registered scenarios to validate on (default :data:`SELECTION_SCENARIOS`).
    """

    def __init__(
        self,
        config: AgentConfig,
        run_dir: str | Path,
        freq: int,
        episodes: int = 30,
        scenarios: Sequence[str] = SELECTION_SCENARIOS,
        verbose: int = 0,
    ) -> None:
        super().__init__(verbose)
        for name, value in (("freq", freq), ("episodes", episodes)):
            if not (isinstance(value, int) and not isinstance(value, bool) and value > 0):
                raise ValueError(f"selection {name}={value!r} is invalid: must be an integer > 0")
        self.config = config
        self.run_dir = Path(run_dir)
        self.freq = freq
        self.episodes = episodes
        self.scenarios = tuple(scenarios)
        self.history: list[dict[str, float]] = []
        """One entry per evaluation: timestep, success_rate, plane_rms_rad."""
        self.best: dict[str, float] | None = None
        self._next = freq

    def _on_training_start(self) -> None:
        # A continued run (--trained-agent) starts at its model's step count: validate the policy it
        # starts from (it is a candidate too), then every freq steps from there.
        start = self.model.num_timesteps
        self._next = start + self.freq
        if start > 0:
            self.num_timesteps = start
            self._evaluate()

    def _on_step(self) -> bool:
        if self.num_timesteps >= self._next:
            self._next += self.freq
            self._evaluate()
        return True

    def _on_training_end(self) -> None:
        if not self.history or self.history[-1]["timestep"] != self.num_timesteps:
            self._evaluate()

    def _evaluate(self) -> None:
        venv = self.model.get_vec_normalize_env()
        agent = TrainedAgent.from_model(
            self.run_dir / SELECTED_DIR / MODEL_FILE,
            self.model,
            self.config,
            venv if venv is not None and venv.norm_obs else None,
        )
        score = {"timestep": self.num_timesteps, **validation_score(agent, self.scenarios, self.episodes)}
        self.history.append(score)
        self.logger.record("selection/success_rate", score["success_rate"])
        self.logger.record("selection/plane_rms_rad", score["plane_rms_rad"])
        best = self.best
        if best is None or (score["success_rate"], -score["plane_rms_rad"]) > (
            best["success_rate"],
            -best["plane_rms_rad"],
        ):
            self.best = score
            self._save(venv)
        if self.verbose:
            tqdm.write(
                f"selection at {self.num_timesteps} steps: success {100 * score['success_rate']:.1f}%, "
                f"plane RMS {score['plane_rms_rad']:.4f} rad (best: {self.best['timestep']})"
            )
        self._write_record()

    def _save(self, venv: Any) -> None:
        with atomic_output_dir(self.run_dir / SELECTED_DIR, overwrite=True) as tmp:
            save_model(self.model, tmp / MODEL_FILE)
            if venv is not None:
                save_statistics(venv, tmp / VECNORMALIZE_FILE)
            atomic_write_bytes(tmp / CONFIG_FILE, (self.run_dir / CONFIG_FILE).read_bytes())

    def _write_record(self) -> None:
        atomic_write_text(
            self.run_dir / SELECTION_FILE,
            json.dumps(
                {
                    "scenarios": list(self.scenarios),
                    "episodes": self.episodes,
                    "seed": VALIDATION_SEED,
                    "best": self.best,
                    "history": self.history,
                },
                indent=2,
            )
            + "\n",
        )

    def record(self) -> dict[str, Any]:
        """What ``train.json`` keeps of the selection."""
        return {
            "scenarios": list(self.scenarios),
            "episodes": self.episodes,
            "validation_seed": VALIDATION_SEED,
            "freq": self.freq,
            "best": self.best,
            "evaluations": len(self.history),
        }
