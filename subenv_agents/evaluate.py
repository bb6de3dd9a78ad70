r"""Evaluate trained agents with the harness of ``subenv evaluate``, next to the classical baselines.

::

    python -m subenv_agents.evaluate results/agents/ppo/subenv-DivePlane-v0_1 --suite reversal
    python -m subenv_agents.evaluate subenv_agents/models/ppo subenv_agents/models/sac \
        --against reversal_aware,lqr

Each path is a run folder, a shipped model folder or a model file (:func:`subenv_agents.load_agent`);
the agent is named after its folder unless ``NAME=PATH`` is given. The results folder is the same
as ``subenv evaluate``'s (leaderboard, summary, per-episode table, plots).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from subenv_agents.controller import AgentController

__all__ = ["agent_controllers", "main"]


def agent_controllers(specs: Sequence[str]) -> list[AgentController]:
    """Controllers from ``PATH`` or ``NAME=PATH`` strings (name: the folder's name by default)."""
    out = []
    for spec in specs:
        name, sep, path = spec.partition("=")
        if not sep:
            name, path = "", spec
        folder = Path(path)
        default = (folder if folder.is_dir() else folder.parent).name
        out.append(AgentController(folder, name=name or default))
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m subenv_agents.evaluate``: compare the agents at the given paths with the baselines on
    a suite, print the leaderboard and write the results folder; returns the exit status."""
    from subenv.evaluation import DEFAULT_SEED, run_comparison

    parser = argparse.ArgumentParser(
        prog="python -m subenv_agents.evaluate", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "agents", nargs="+", metavar="[NAME=]PATH", help="run folders, model folders or model files"
    )
    parser.add_argument(
        "--against",
        default="reversal_aware",
        help="comma-separated registered controllers to compare with ('' for none; default: %(default)s)",
    )
    parser.add_argument(
        "--suite", default="default", help="suite name or comma-separated scenarios (default: %(default)s)"
    )
    parser.add_argument("--episodes", type=int, help="episodes per scenario (default: the suite's)")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED, help="base seed (default: %(default)s)")
    parser.add_argument("--out", help="results folder (default: results/evaluation/agents-<date-time>)")
    parser.add_argument("--force", action="store_true", help="replace the results folder if it exists")
    parser.add_argument("--no-plots", action="store_true", help="write tables only")
    args = parser.parse_args(argv)
    try:
        controllers: list[Any] = agent_controllers(args.agents)
        controllers += [name for name in args.against.split(",") if name]
        suite = args.suite.split(",") if "," in args.suite else args.suite
        out = args.out or f"results/evaluation/agents-{time.strftime('%Y%m%d-%H%M%S')}"
        comparison = run_comparison(
            controllers,
            suite,
            args.episodes,
            out,
            overwrite=args.force,
            seed=args.seed,
            progress=sys.stderr.isatty(),
            plots=not args.no_plots,
        )
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        raise SystemExit(f"subenv_agents.evaluate: {exc}") from None
    print(comparison.leaderboard)
    print(
        f"\n{len(comparison.results)} episodes in {comparison.elapsed_s:.1f} s; results in "
        f"{comparison.out_dir}/"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
