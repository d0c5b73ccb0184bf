"""Benchmark: start-up cost of ``import tenscell`` and ``tenscell --help``.

Each command runs as a fresh interpreter, interleaved with the floor — a bare
``python -c pass`` — in the same run, so machine load affects both alike.
Prints medians and the differences against the floor, and the modules the
import pulls in that it should not.

Goals (issue 11): ``import tenscell`` within 0.4 s of the floor, ``tenscell
--help`` within 0.15 s of it.
"""
from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPEAT = 15
HEAVY = ("numpy", "scipy", "scipy.optimize", "matplotlib", "pandas")


def cli_command() -> list[str]:
    """The installed ``tenscell`` entry point, as a user runs it (else ``python -m tenscell.cli``)."""
    script = Path(sys.executable).with_name("tenscell")
    found = str(script) if script.exists() else shutil.which("tenscell")
    return [found] if found else [sys.executable, "-m", "tenscell.cli"]


def run_once(cmd: list[str]) -> float:
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    t = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, env=env)
    return time.perf_counter() - t


def loaded_by_import() -> list[str]:
    code = f"import sys, tenscell; print(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def main() -> None:
    commands = {
        "python -c pass (floor)": [sys.executable, "-c", "pass"],
        "import tenscell": [sys.executable, "-c", "import tenscell"],
        "tenscell --help": cli_command() + ["--help"],
        "import + paper_cell() (for scale)": [sys.executable, "-c", "import tenscell; tenscell.paper_cell()"],
    }
    goals = {"import tenscell": 0.4, "tenscell --help": 0.15}
    times: dict[str, list[float]] = {k: [] for k in commands}
    for cmd in commands.values():  # warm the file cache and byte-code
        run_once(cmd)
    for _ in range(REPEAT):  # interleaved, so a burst of load hits every command
        for name, cmd in commands.items():
            times[name].append(run_once(cmd))
    floor = statistics.median(times["python -c pass (floor)"])
    print(f"bench_startup: {REPEAT} interleaved runs each, medians (s)")
    for name, ts in times.items():
        med = statistics.median(ts)
        line = f"  {name:36s} {med:7.3f}   floor + {med - floor:6.3f}   x{med / floor:5.1f}"
        if name in goals:
            line += f"   (goal: floor + {goals[name]:.2f}: {'met' if med - floor <= goals[name] else 'NOT met'})"
        print(line)
    heavy = loaded_by_import()
    print(f"  heavy modules loaded by 'import tenscell': {', '.join(heavy) or 'none'}")


if __name__ == "__main__":
    main()
