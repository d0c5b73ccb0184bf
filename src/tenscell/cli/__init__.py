"""The ``tenscell`` command line: parse arguments, call the library, write output sets.

One module per command group; each has ``register(subparsers)`` (standard
library only, so that building the parser is quick) and run functions that
import the library when they run. Adding a command is one line in
:data:`COMMAND_MODULES`.

:func:`main` returns the exit status (also for ``--help`` and refused flags)
instead of raising SystemExit. Exit status: 0 success, 1 a fit that did not reach its tolerance, 2 bad
input (one line on stderr naming the flag, before any computation, nothing
written), 70 internal error (a bug in tenscell, not the input: one line on stderr
naming the log file that holds the command, what it printed, i.e. what it had
computed, and the traceback; nothing written), 130 interrupted (Ctrl-C), 141 output
pipe closed.
"""
from __future__ import annotations

import argparse
import importlib
import io
import os
import sys
import time
import warnings

from ._args import Parser, check_stdout, command_line

__all__ = ["main", "build_parser", "COMMAND_MODULES", "EXIT_INTERNAL"]

#: exit status of an internal error: a bug in tenscell, not bad input (EX_SOFTWARE of sysexits.h)
EXIT_INTERNAL = 70

#: command modules, in the order their commands appear in --help; each has ``register(sub)``
COMMAND_MODULES = (
    "moduli",
    "reproduce",
    "fit",
    "dynamics",
    "study",
    "show",
    "population",
)


#: the end of `tenscell --help`: the question a lab asks first and what to type, then the exit statuses (kept as
#: written: the commands must not be broken across lines)
_EPILOG = """\
Which mechanism fits my cells, and does its structure explain them? Fit every mechanism to your own files
(CSV/TSV/Excel tables, TA TRIOS or Anton Paar RheoCompass exports, creep
tables; several files are fitted jointly) and compare them on one table
(it prints its estimated time before it starts):

  tenscell study mechanisms MY_SWEEP.csv MY_PRESTRESS_SWEEP.csv --out mechanisms/

Then fit one mechanism, reported beside its own structure-free formula
({model} is the recommended first model; `tenscell fit --help`
lists every --model), and ask it about prestresses and frequencies it never saw
(with a frequency sweep alone, leave --prestress out):

  tenscell fit MY_SWEEP.csv MY_PRESTRESS_SWEEP.csv --model {model} --out fit/
  tenscell moduli --from-fit fit/fit.json --prestress 500,1000 --freq 0.01:100:41

The paper itself: `tenscell reproduce`.

Exit status: 0 success; 1 a fit that did not reach its tolerance; 2 bad input
(one line naming the flag or the file and line, nothing computed or written);
{internal} an internal error (a bug, not your input: one line naming a log file);
130 interrupted (Ctrl-C)."""


class _TopHelp(argparse.RawDescriptionHelpFormatter):
    """The top-level help: the epilog as written (its command lines intact)."""


def _version() -> str:
    from .. import __version__
    return __version__


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand (imports only the standard library)."""
    from .fit import RECOMMENDED_MODEL

    parser = Parser(
        prog="tenscell",
        description="Tensegrity models of the cytoskeleton: moduli G'(f, P), G''(f, P), fits and studies.",
        epilog=_EPILOG.format(model=RECOMMENDED_MODEL, internal=EXIT_INTERNAL),
        formatter_class=_TopHelp,
    )
    parser.add_argument("--version", action="version", version=f"tenscell {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def _quiet_broken_pipe() -> int:
    """stdout's reader went away (``tenscell moduli | head -1``): stop quietly."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout without a file descriptor (captured in tests)
        pass
    return 141


def main(argv=None) -> int:
    """Entry point of the ``tenscell`` command; returns the exit status.

    As the console command (``argv`` None) it ends the process itself once the
    command is done: its outputs are complete and flushed by then, and the
    interpreter's teardown of numpy, scipy and matplotlib (0.1–0.2 s, measured)
    adds nothing to them.
    """
    started = time.monotonic()  # the command's own clock (fit.json's "timing")
    transcript = _Transcript(sys.stderr)
    sys.stderr = transcript
    try:
        status = _run(argv, started, transcript)
    finally:
        if sys.stderr is transcript:
            sys.stderr = transcript.stream
    if argv is None:
        _exit_now(status)
    return status


def _parse(parser, argv):
    """The parsed command line; data files may also follow options (``study NAME --draws 3 DATA``).

    argparse fills a command's trailing ``data`` positional (nargs="*") as soon as it meets the positional before it,
    so files typed after an option come back unrecognized: they are appended to ``data`` in the order typed.
    Anything else unrecognized is refused by argparse as usual (one line, status 2).
    """
    args, extra = parser.parse_known_args(argv)
    if extra:
        if isinstance(getattr(args, "data", None), list) and not any(e.startswith("-") for e in extra):
            args.data = [*args.data, *extra]
        else:
            parser.parse_args(argv)  # reports the unrecognized arguments and exits with status 2
    return args


def _run(argv, started: float, transcript: "_Transcript") -> int:
    # The command writes files and never opens windows; the library itself never chooses a backend.
    os.environ.setdefault("MPLBACKEND", "Agg")
    # after Ctrl-C, multiprocessing's resource tracker (a separate process, used by Dask's workers) reports the
    # semaphores of the stopped workers as a UserWarning while it frees them: not the user's concern
    _quiet = "ignore::UserWarning:multiprocessing.resource_tracker"
    if _quiet not in os.environ.get("PYTHONWARNINGS", ""):
        os.environ["PYTHONWARNINGS"] = ",".join(filter(None, (os.environ.get("PYTHONWARNINGS"), _quiet)))
    args = None
    try:
        try:
            args = _parse(build_parser(), argv)
        except SystemExit as stop:  # --help, --version, or a flag refused by the parser (one line, status 2)
            return stop.code if isinstance(stop.code, int) else 2
        args.command_line = command_line(argv)
        args.started = started
        check_stdout(args.command)  # results on standard output: it must take them, before any work
        with warnings.catch_warnings():
            # floating-point warnings never reach the user: inputs are range-checked and
            # results checked for finiteness where an overflow is possible
            warnings.simplefilter("ignore", RuntimeWarning)
            return int(args.func(args) or 0)
    except KeyboardInterrupt as stop:
        # one line: a command may say what it kept (KeyboardInterrupt("tenscell CMD: interrupted; ..."))
        line = stop.args[0] if stop.args and isinstance(stop.args[0], str) else "tenscell: interrupted"
        print(line, file=sys.stderr, flush=True)
        # the console command leaves at once (main): workers are stopped and output staging removed by now
        return 130
    except BrokenPipeError:
        return _quiet_broken_pipe()
    except (ValueError, OSError, RecursionError) as err:
        print(f"{_prog(args)}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"{_prog(args)}: error: out of memory; reduce the size of the run", file=sys.stderr)
        return 2
    except Exception as err:  # not bad input: a bug; the user gets one line and where the details are
        log = _write_log(args, argv, err, transcript.text())
        where = f"details in {log}" if log else "no log could be written"
        print(f"{_prog(args)}: internal error (a bug in tenscell, not in your input): "
              f"{type(err).__name__}: {_one_line(err)}; {where}", file=sys.stderr)
        return EXIT_INTERNAL


class _Transcript(io.TextIOBase):
    """stderr as it was, keeping the last lines written to it (the stage lines: what the command computed)."""

    _KEEP = 200

    def __init__(self, stream):
        super().__init__()
        self.stream = stream
        self._lines: list[str] = []

    def write(self, s: str) -> int:
        written = self.stream.write(s)
        if "\r" not in s:  # progress bars redraw with \r: their frames are not kept
            self._lines.extend(s.splitlines(keepends=True))
            del self._lines[:-self._KEEP]
        return written if written is not None else len(s)

    def flush(self) -> None:
        self.stream.flush()

    def isatty(self) -> bool:
        return self.stream.isatty()

    def fileno(self) -> int:
        return self.stream.fileno()

    @property
    def encoding(self):
        return getattr(self.stream, "encoding", "utf-8")

    def text(self) -> str:
        return "".join(self._lines)


def _write_log(args, argv, err: BaseException, printed: str) -> str | None:
    """Write what an internal error needs for a report into a file of its own: its path (None if it could not)."""
    import datetime
    import tempfile
    import traceback

    from .. import __version__

    stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%SZ")
    lines = [
        f"tenscell {__version__}: internal error at {stamp}",
        f"command: {getattr(args, 'command_line', None) or command_line(argv)}",
        " ".join([f"python {sys.version.split()[0]} on {sys.platform}",
                  *(f"{m} {sys.modules[m].__version__}" for m in ("numpy", "scipy") if m in sys.modules)]),
        "environment: " + ", ".join(f"{k}={v}" for k, v in sorted(os.environ.items())
                                       if k.startswith(("TENSCELL_", "OPENBLAS_", "OMP_", "MKL_"))),
        "", "what the command printed (its stages: what it had computed):", printed.rstrip() or "(nothing)",
        "", "traceback:", "".join(traceback.format_exception(type(err), err, err.__traceback__)).rstrip(), "",
    ]
    try:
        fd, path = tempfile.mkstemp(prefix=f"tenscell-error-{stamp}-", suffix=".log")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write("\n".join(lines))
    except OSError:
        return None
    return path


def _prog(args) -> str:
    command = getattr(args, "command", None)
    return f"tenscell {command}" if command else "tenscell"


#: longest error message printed (a message quoting a huge input value is cut)
_MAX_MESSAGE = 600


def _one_line(err: BaseException) -> str:
    """The error's message for the user: options spelled as flags (``_args.user_message``), on one line."""
    from ._args import user_message

    text = " ".join(user_message(err).split()) or type(err).__name__
    return text if len(text) <= _MAX_MESSAGE else text[:_MAX_MESSAGE - 1] + "…"


def _exit_now(status: int) -> None:
    """Run the exit handlers, flush the standard streams and end the process without module teardown.

    The exit handlers release what other processes track (multiprocessing's semaphores, Dask's
    clusters); only the slow garbage collection of the loaded modules is skipped.
    """
    import atexit
    try:
        atexit._run_exitfuncs()
    except BaseException:  # an exit handler that fails or is interrupted must not keep us here
        pass
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):  # AttributeError: a closed descriptor made it None
            pass
    os._exit(status)
