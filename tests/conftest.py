"""Session-wide test settings."""
from __future__ import annotations

import signal

import pytest


@pytest.fixture(scope="session", autouse=True)
def _sigint_not_ignored():
    """Children started by the tests see Ctrl-C (SIGINT) as a user's terminal delivers it.

    A test runner started with SIGINT ignored (``nohup``, or a background job ``&`` of a
    non-interactive shell, as CI scripts do) passes the ignoring on to every process it starts,
    across exec: the interrupt tests' SIGINT then never reaches ``tenscell``, which runs to its end
    (exit 0 or 1 instead of 130). Python's own handler is restored for the session, and the
    previous disposition afterwards.
    """
    previous = signal.getsignal(signal.SIGINT)
    if previous == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    if previous == signal.SIG_IGN:
        signal.signal(signal.SIGINT, previous)
