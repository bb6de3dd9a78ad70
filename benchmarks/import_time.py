"""How long ``import subenv`` takes, next to ``import gymnasium, numba`` (what it cannot do without).

    .venv/bin/python benchmarks/import_time.py [--repeats 7]

Each import runs in a fresh interpreter (nothing cached in the process; the operating system's file
cache warm after the first run), timed inside it from before the import statement to after it, so
the interpreter's own start is left out. The two take turns, ``--repeats`` times each; the best of
each is kept (machines share their cores) and their ratio printed. The target of issue 33: at most
2x. ``python -X importtime -c "import subenv"`` shows what the time goes to.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
IMPORTS = {"subenv": "import subenv", "reference": "import gymnasium, numba"}
_TIMED = "import time; start = time.perf_counter(); {statement}; print(time.perf_counter() - start)"


def import_seconds(statement: str) -> float:
    """Seconds ``statement`` takes in a fresh interpreter (this checkout's subenv first on the path)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run(
        [sys.executable, "-c", _TIMED.format(statement=statement)],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return float(out.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--repeats", type=int, default=7, help="runs of each, best kept (default: %(default)s)"
    )
    args = parser.parse_args()
    for statement in IMPORTS.values():  # (warm the file cache)
        import_seconds(statement)
    best = dict.fromkeys(IMPORTS, float("inf"))
    for _ in range(args.repeats):
        for key, statement in IMPORTS.items():
            best[key] = min(best[key], import_seconds(statement))
    print("| import | best of", args.repeats, "[ms] |")
    print("|---|---:|")
    for key, statement in IMPORTS.items():
        print(f"| `{statement}` | {best[key] * 1e3:.0f} |")
    print(
        f"\nimport subenv / import gymnasium, numba: {best['subenv'] / best['reference']:.2f} (target: <= 2)"
    )


if __name__ == "__main__":
    main()
