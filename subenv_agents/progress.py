"""Training progress that shows on a terminal and in a log file alike."""

from __future__ import annotations

from stable_baselines3.common.callbacks import BaseCallback

from subenv.evaluation.progress import Progress

__all__ = ["TrainingProgress"]


class TrainingProgress(BaseCallback):
    """Counts the steps trained on :class:`subenv.evaluation.progress.Progress` (stderr).

    On a terminal a tqdm bar, above which SB3's log tables (its ``HumanOutputFormat`` prints through
    ``tqdm.write``) and the callbacks' lines are printed, never through it; otherwise a line every 5%
    with the time left, so that a log file shows the run is alive. SB3's own ``progress_bar`` (a rich
    display that ``tqdm.write`` does not clear) is not used.
    """

    def __init__(self, total_steps: int, enabled: bool = True) -> None:
        super().__init__()
        self.total_steps, self.enabled = total_steps, enabled
        self.bar: Progress | None = None

    def _on_training_start(self) -> None:
        self.bar = Progress(self.total_steps, enabled=self.enabled, label="train", unit="step")

    def _on_step(self) -> bool:
        assert self.bar is not None
        self.bar.update(self.training_env.num_envs)
        return True

    def _on_training_end(self) -> None:
        if self.bar is not None:
            self.bar.close()
