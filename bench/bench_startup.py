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
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPEAT = 15
HEAVY = ("numpy", "scipy", "scipy.optimize", "matplotlib", "pandas")


def cli_command() -> list[str]:
    """The installed ``tenscell`` entry point, as a user runs it (else ``python -m tenscell.cli``)."""
    script = Path(sys.executable).with_name("tenscell")
    found = str(script) if script.exists() else shutil.which("tenscell")
    return [found] if found else [sys.executable, "-m", "tenscell.cli"]


def child_env(cache: str) -> dict[str, str]:
    """Byte-code cached in ``cache`` (as an installed package has it), whatever the caller's settings."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = cache
    return env


def run_once(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of one run of ``cmd``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, env=env)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


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
    wall: dict[str, list[float]] = {k: [] for k in commands}
    cpu: dict[str, list[float]] = {k: [] for k in commands}
    with tempfile.TemporaryDirectory() as cache:
        env = child_env(cache)
        for cmd in commands.values():  # warm the file cache and write the byte-code
            run_once(cmd, env)
        for _ in range(REPEAT):  # interleaved, so a burst of load hits every command
            for name, cmd in commands.items():
                w, c = run_once(cmd, env)
                wall[name].append(w)
                cpu[name].append(c)
    floor_w, floor_c = statistics.median(wall["python -c pass (floor)"]), statistics.median(cpu["python -c pass (floor)"])
    print(f"bench_startup: {REPEAT} interleaved runs each, medians in s (CPU = user + system, "
          "the steadier figure on a loaded machine)")
    for name in commands:
        w, c = statistics.median(wall[name]), statistics.median(cpu[name])
        line = f"  {name:36s} wall {w:6.3f} (floor + {w - floor_w:6.3f})   CPU {c:6.3f} (floor + {c - floor_c:6.3f})"
        if name in goals:
            met = "met" if w - floor_w <= goals[name] else "NOT met"
            line += f"   goal floor + {goals[name]:.2f}: {met} (wall)"
        print(line)
    heavy = loaded_by_import()
    print(f"  heavy modules loaded by 'import tenscell': {', '.join(heavy) or 'none'}")


if __name__ == "__main__":
    main()
