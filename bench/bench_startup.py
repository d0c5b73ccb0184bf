"""Benchmark: start and draw — ``import tenscell``, ``tenscell --help``, ``tenscell moduli``, ``tenscell show block``.

Each command runs as a fresh interpreter (byte-code cached, as an installed
package has it), interleaved with its floor in the same run, so machine load
affects both alike. Prints medians and the differences against the floors, in
wall and CPU (user + system) seconds, with the load average.

Goals:

* issue 11: ``import tenscell`` within 0.4 s of ``python -c pass`` (wall),
  ``tenscell --help`` within 0.15 s of it (wall);
* issue 29: ``tenscell moduli`` (its default request) within 0.15 s of CPU of
  ``python -c "import numpy, scipy.linalg"`` (what any command computing with
  the model needs); printed with what the ``tenscell.io`` package's own modules
  take of it (``python -X importtime``, the part the lazy ``io`` package removes)
  and the heavy modules the command loads;
* issue 29: ``tenscell show block --size 11x11x12`` at most 3 s of CPU, with the
  CPU of each stage measured in one process (build, summary and linearization,
  the slowest modes, drawing).

``--quick`` leaves out ``show block`` (about 5 s a run).
"""
from __future__ import annotations

import argparse
import json
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
SHOW_REPEAT = 3
HEAVY = ("numpy", "scipy", "scipy.optimize", "matplotlib", "pandas")
#: modules the moduli command should not load (it computes with scipy.linalg and scipy.sparse only)
UNUSED_BY_MODULI = ("scipy.optimize", "scipy.special", "scipy.integrate", "scipy.stats", "matplotlib", "pandas",
                    "dask", "distributed", "pyarrow")
MODULI_GOAL_CPU_S = 0.15
SHOW_GOAL_CPU_S = 3.0
SHOW_ARGS = ["show", "block", "--size", "11x11x12"]


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


def interleaved(commands: dict[str, list[str]], env: dict[str, str], repeat: int) -> dict[str, tuple[float, float]]:
    """Median (wall, CPU) seconds of each command, run ``repeat`` times interleaved after one warm-up run each."""
    wall: dict[str, list[float]] = {k: [] for k in commands}
    cpu: dict[str, list[float]] = {k: [] for k in commands}
    for cmd in commands.values():  # warm the file cache and write the byte-code
        run_once(cmd, env)
    for _ in range(repeat):  # interleaved, so a burst of load hits every command
        for name, cmd in commands.items():
            w, c = run_once(cmd, env)
            wall[name].append(w)
            cpu[name].append(c)
    return {k: (statistics.median(wall[k]), statistics.median(cpu[k])) for k in commands}


def io_import_ms(cmd_code: str, env: dict[str, str], repeat: int = 5) -> float:
    """Median milliseconds the ``tenscell.io`` package's own modules take to import in ``cmd_code`` (importtime)."""
    totals = []
    for _ in range(repeat):
        err = subprocess.run([sys.executable, "-X", "importtime", "-c", cmd_code], capture_output=True, text=True,
                             env=env, check=True).stderr
        us = 0
        for line in err.splitlines():
            if line.startswith("import time:") and "|" in line:
                self_us, _, name = line.split(":", 1)[1].split("|")
                if name.strip() == "tenscell.io" or name.strip().startswith("tenscell.io."):
                    us += int(self_us)
        totals.append(us / 1000.0)
    return statistics.median(totals)


def loaded_by_moduli(env: dict[str, str]) -> list[str]:
    code = ("import contextlib, io, sys\nfrom tenscell.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n    main(['moduli'])\n"
            f"print(' '.join(m for m in {UNUSED_BY_MODULI!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return out.stdout.split()


def show_stages() -> dict[str, float]:
    """CPU seconds of each stage of ``tenscell show block --size 11x11x12``, as the command runs them, in this process."""
    import tempfile

    t = time.process_time()
    from tenscell import plotting
    from tenscell.cli.show import MODES_TOL
    from tenscell.io.structure_files import member_values
    from tenscell.model import lattices
    from tenscell.summary import relaxation_modes, summarize

    stages = {"imports (numpy, scipy, matplotlib, tenscell)": time.process_time() - t}
    t = time.process_time()
    cell = lattices.lattice_cell(11, 11, 12)
    EA = member_values(cell.structure, {"strut": lattices.LATTICE_STRUT_EA, "default": 1.0}, "--EA", "N")
    stages["build the lattice"], t = time.process_time() - t, time.process_time()
    _, _, lin = summarize(cell, P=1000.0, EA=EA, c=1.0)
    stages["summary, linearization, K0 factor"], t = time.process_time() - t, time.process_time()
    modes = relaxation_modes(lin, 3, tol=MODES_TOL)  # as the command asks: the accuracy it prints
    stages["3 slowest modes (shifted Lanczos, linear/krylov)"], t = time.process_time() - t, time.process_time()
    with tempfile.TemporaryDirectory() as d:
        plotting.save(plotting.structure_3d(cell.structure), f"{d}/s.png")
        plotting.save(plotting.relaxation_modes_3d(cell.structure, modes.rates, modes.displacements), f"{d}/m.png")
    stages["drawing (structure and modes figures)"] = time.process_time() - t
    return stages


def _verdict(ok: bool) -> str:
    return "met" if ok else "NOT met"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="leave out show block (about 5 s a run)")
    ap.add_argument("--stages", action="store_true", help=argparse.SUPPRESS)  # the child run of show_stages
    args = ap.parse_args()
    if args.stages:
        print(json.dumps(show_stages()))
        return
    tenscell = cli_command()
    commands = {
        "python -c pass (floor)": [sys.executable, "-c", "pass"],
        "import tenscell": [sys.executable, "-c", "import tenscell"],
        "tenscell --help": tenscell + ["--help"],
        "import + paper_cell() (for scale)": [sys.executable, "-c", "import tenscell; tenscell.paper_cell()"],
        "import numpy, scipy.linalg (floor)": [sys.executable, "-c", "import numpy, scipy.linalg"],
        "tenscell moduli": tenscell + ["moduli"],
    }
    goals = {"import tenscell": 0.4, "tenscell --help": 0.15}
    print(f"bench_startup: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start; {REPEAT} "
          "interleaved runs each, medians in s (CPU = user + system, the steadier figure on a loaded machine)")
    with tempfile.TemporaryDirectory() as cache:
        env = child_env(cache)
        med = interleaved(commands, env, REPEAT)
        floor_w, floor_c = med["python -c pass (floor)"]
        for name in list(commands)[:4]:
            w, c = med[name]
            line = f"  {name:36s} wall {w:6.3f} (floor + {w - floor_w:6.3f})   CPU {c:6.3f} (floor + {c - floor_c:6.3f})"
            if name in goals:
                line += f"   goal floor + {goals[name]:.2f}: {_verdict(w - floor_w <= goals[name])} (wall)"
            print(line)
        heavy = loaded_by_import()
        print(f"  heavy modules loaded by 'import tenscell': {', '.join(heavy) or 'none'}")

        (sw, sc), (mw, mc) = med["import numpy, scipy.linalg (floor)"], med["tenscell moduli"]
        print(f"  {'import numpy, scipy.linalg (floor)':36s} wall {sw:6.3f}   CPU {sc:6.3f}")
        print(f"  {'tenscell moduli':36s} wall {mw:6.3f} (floor + {mw - sw:6.3f})   CPU {mc:6.3f} "
              f"(floor + {mc - sc:6.3f} = {mc / sc:.2f}x)   goal floor + {MODULI_GOAL_CPU_S:.2f} CPU: "
              f"{_verdict(mc - sc <= MODULI_GOAL_CPU_S)}")
        run_moduli = ("import numpy, scipy.linalg, contextlib, io\nfrom tenscell.cli import main\n"
                      "with contextlib.redirect_stdout(io.StringIO()):\n    main(['moduli'])")
        print(f"    of which the tenscell.io package's own modules: {io_import_ms(run_moduli, env):.1f} ms "
              "(python -X importtime, median of 5)")
        unused = loaded_by_moduli(env)
        print(f"    modules it loads and does not use: {', '.join(unused) or 'none'}")

        if args.quick:
            return
        show = interleaved({"show": tenscell + SHOW_ARGS + ["--out", f"{cache}/show"]}, env, SHOW_REPEAT)["show"]
        print(f"  tenscell {' '.join(SHOW_ARGS):34s} wall {show[0]:6.3f}   CPU {show[1]:6.3f} (median of "
              f"{SHOW_REPEAT}; load {os.getloadavg()[0]:.2f})   goal <= {SHOW_GOAL_CPU_S:.1f} s CPU: "
              f"{_verdict(show[1] <= SHOW_GOAL_CPU_S)}")
        out = subprocess.run([sys.executable, __file__, "--stages"], capture_output=True, text=True, check=True,
                             env=env)
        for stage, cpu_s in json.loads(out.stdout.splitlines()[-1]).items():
            print(f"    {stage:48s} CPU {cpu_s:6.3f}")


if __name__ == "__main__":
    main()
