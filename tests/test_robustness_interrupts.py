"""Interrupts, kills and broken pipes: clean stops, no stray processes, output sets old or new, never mixed.

Subprocess tests send real signals to `python -m tenscell`; the property test
drives :class:`~tenscell.io.outputs.OutputSet` through runs that fail at
random points (hypothesis) and checks that the directory always holds the
previous complete set or the new complete set.
"""
from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tenscell.io import outputs
from tenscell.io.data import bundled
from tenscell.io.outputs import MANIFEST, OutputSet

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

ENV = {**os.environ, "MPLBACKEND": "Agg", "TENSCELL_PROGRESS": "0"}
#: generous bound that only a hang can exceed (the measured stop takes well under a second)
HANG_S = 15.0


def _children(pid: int) -> list[int]:
    kids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                kids.append(int(entry))
    return kids


def _running(pid: int) -> bool:
    """Alive and not a zombie (a dead worker waiting for its reaper counts as gone)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def _wait_for_children(p, n: int, timeout: float = 120.0) -> list[int]:
    end = time.monotonic() + timeout
    while time.monotonic() < end and p.poll() is None:
        kids = [k for k in _children(p.pid) if _running(k)]
        if len(kids) >= n:
            return kids
        time.sleep(0.02)
    raise AssertionError("the parallel fit never started its workers")


def _previous_set(d: Path) -> dict:
    with OutputSet(d, command="tenscell fit earlier.csv --out x") as s:
        (s / "fit.json").write_text('{"earlier": true}')
        (s / "fit.png").write_bytes(b"old png")
    return _snapshot(d)


def _snapshot(d: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def _fit_process(out: Path):
    data = str(out.parent / "fabry.csv")
    if not Path(data).exists():
        from tenscell.io.data import write_csv
        write_csv(bundled("fabry2001"), data)
    # a tolerance out of reach keeps the search going for seconds: the signal lands inside the fit
    return subprocess.Popen([sys.executable, "-m", "tenscell", "fit", data, "--starts", "4", "--jobs", "2",
                             "--tolerance", "1e-5", "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=ENV)


def test_ctrl_c_during_a_parallel_fit(tmp_path):
    """SIGINT at random points of a parallel fit: exit 130, one line, no worker left, old set intact."""
    out = tmp_path / "fit"
    before = _previous_set(out)
    rng = random.Random(13)
    latencies = []
    for trial in range(4):
        p = _fit_process(out)
        workers = _wait_for_children(p, 2)
        time.sleep(rng.uniform(0.0, 1.5))
        t = time.monotonic()
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=HANG_S)
        latencies.append(time.monotonic() - t)
        assert p.returncode == 130, err
        assert err == "tenscell: interrupted\n", err
        deadline = time.monotonic() + 2.0
        while any(_running(w) for w in workers) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not any(_running(w) for w in workers), f"trial {trial}: a worker survived"
        assert _snapshot(out) == before, f"trial {trial}: the previous output set changed"
        assert sorted(x.name for x in tmp_path.iterdir()) == ["fabry.csv", "fit"], "staging left behind"
    assert max(latencies) < HANG_S


def test_kill_9_of_the_main_process_takes_the_workers(tmp_path):
    out = tmp_path / "fit"
    before = _previous_set(out)
    p = _fit_process(out)
    workers = _wait_for_children(p, 2)
    p.kill()
    p.communicate()
    deadline = time.monotonic() + 5.0
    while any(_running(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not any(_running(w) for w in workers), "workers outlived a killed main process"
    assert _snapshot(out) == before
    # the dead run's staging (if it got that far) is cleaned by the next run that writes beside it
    OutputSet(out, command="tenscell fit again.csv")
    assert sorted(x.name for x in tmp_path.iterdir()) == ["fabry.csv", "fit"]


def test_broken_pipe_is_quiet(tmp_path):
    p = subprocess.Popen([sys.executable, "-m", "tenscell", "moduli", "--freq", "0.01:1000:200000"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
    first = p.stdout.readline()
    p.stdout.close()  # `| head -1`
    err = p.stderr.read().decode()
    p.wait(timeout=HANG_S)
    assert first.startswith(b"prestress_Pa,")
    assert err == "" and p.returncode == 141


def test_kill_9_while_writing_a_set_leaves_old_or_new(tmp_path):
    """A writer killed at random moments (even inside the swap): the next run finds a complete set."""
    target = tmp_path / "o"
    code = ("import sys, time\nfrom tenscell.io.outputs import OutputSet\n"
            "n = int(sys.argv[2])\n"
            "with OutputSet(sys.argv[1], command='tenscell test ' + sys.argv[2]) as d:\n"
            "    for i in range(n):\n"
            "        (d / f'f{i}.txt').write_text(sys.argv[2])\n"
            "        time.sleep(0.002)\n"
            "print('done', flush=True)\n")
    rng = random.Random(7)
    for trial in range(6):
        p = subprocess.Popen([sys.executable, "-c", code, str(target), str(200 + trial)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
        time.sleep(rng.uniform(0.05, 0.8))
        p.kill()
        p.communicate()
        OutputSet(target, command="tenscell test x")  # the next run cleans up
        leftovers = [x.name for x in tmp_path.iterdir() if x.name != "o"]
        assert leftovers == []
        if target.exists():
            _assert_complete(target)


def _assert_complete(d: Path) -> None:
    manifest = json.loads((d / MANIFEST).read_text())
    names = sorted(x.name for x in d.iterdir() if x.name != MANIFEST)
    assert names == sorted(manifest["files"])
    tag = manifest["command"].split()[-1]
    assert len(names) == int(tag) and all((d / n).read_text() == tag for n in names)


# ---- property: the directory is always the old complete set or the new one -----------------------
class _Boom(Exception):
    pass


runs = st.lists(st.tuples(st.integers(1, 6),                                   # files in the run
                          st.sampled_from(["ok", "write", "interrupt", "rename", "exchange"]),
                          st.integers(0, 5)),                                   # where the failure strikes
                min_size=1, max_size=6)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(plan=runs)
def test_output_dir_is_always_a_complete_set(tmp_path_factory, monkeypatch, plan):
    base = tmp_path_factory.mktemp("prop")
    target = base / "out"
    last_ok = None
    for k, (n, failure, at) in enumerate(plan):
        tag = f"{k}-{n}"
        with monkeypatch.context() as m:
            if failure == "rename":  # a crash between the two renames of the fallback swap
                m.setattr(outputs, "_exchange", lambda a, b: False)
                real = os.rename
                calls = []

                def rename(a, b, real=real, calls=calls):
                    calls.append(a)
                    if len(calls) == 2:
                        raise _Boom
                    real(a, b)
                m.setattr(outputs.os, "rename", rename)
            elif failure == "exchange":
                m.setattr(outputs, "_exchange", lambda a, b: (_ for _ in ()).throw(_Boom()))
            try:
                with OutputSet(target, command=f"tenscell test {tag}") as d:
                    for i in range(n):
                        if failure in ("write", "interrupt") and i == min(at, n - 1):
                            raise KeyboardInterrupt if failure == "interrupt" else _Boom
                        (d / f"f{i}.txt").write_text(tag)
                last_ok = tag
            except (_Boom, KeyboardInterrupt):
                pass
        # what a later run (or a reader) finds, after the next run's clean-up of dead runs' leftovers
        outputs._clean_stale(target)
        if last_ok is None:
            assert not target.exists() or not any(target.iterdir())
        else:
            manifest = json.loads((target / MANIFEST).read_text())
            tag_found = manifest["command"].split()[-1]
            files = sorted(x.name for x in target.iterdir() if x.name != MANIFEST)
            assert files == sorted(manifest["files"])
            assert all((target / f).read_text() == tag_found for f in files)
            assert len(files) == int(tag_found.split("-")[1])
            assert tag_found == last_ok
        assert [x.name for x in base.iterdir() if x.name != "out"] == []


def _sleep_and_report(seconds: float, pid_file: str | None = None) -> int:
    if pid_file:  # written whole, then renamed: the test never reads half a number
        Path(pid_file + ".tmp").write_text(str(os.getpid()))
        os.replace(pid_file + ".tmp", pid_file)
    time.sleep(seconds)
    return os.getpid()


def test_background_task_returns_its_result_and_dies_with_an_error_in_the_block(tmp_path):
    from tenscell._parallel import background

    with background() as bg:
        first, second = bg.submit(_sleep_and_report, 0.0), bg.submit(_sleep_and_report, 0.0)
        pid = first.result()
        assert second.result() == pid  # one worker, tasks one after another
    assert pid != os.getpid()
    # an exception in the block (as Ctrl-C would be) stops the worker at once, mid-task
    pid_file = tmp_path / "worker.pid"
    with pytest.raises(RuntimeError, match="stop"), background() as bg:
        task = bg.submit(_sleep_and_report, 60.0, str(pid_file))
        deadline = time.monotonic() + 10
        while not pid_file.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        worker = int(pid_file.read_text())
        assert _running(worker)
        raise RuntimeError("stop")
    assert not _running(worker)
    # stopped mid-task, not waited for: a task that had run its 60 s to the end would hold its result
    assert not task.done() or task.cancelled() or task.exception(timeout=0) is not None
