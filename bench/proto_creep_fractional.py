"""Prototype check of G5 (issue 26): a springpot cell's creep J(t) against its exact inverse transform, 1e-3 to 1e3 s.

The reference is the Mittag-Leffler sum over the modes of a cell with one springpot law on every tendon
(tests/test_creep_fractional.py builds it by quadrature, independent of any contour); the package's
``creep_compliance`` (exact inversion of the law's J(s)/s by the fixed Talbot contour) and the realized
spectrum of the default band (1e-2-1e3 Hz) are compared with it, with their CPU times.

Run: .venv/bin/python bench/proto_creep_fractional.py
"""
from __future__ import annotations

import os
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from test_creep_fractional import CELL, T_G5, _uniform_springpot_creep  # noqa: E402

from tenscell.laws import Springpot  # noqa: E402
from tenscell.linear import linearize_law  # noqa: E402
from tenscell.timedomain import creep_compliance  # noqa: E402

print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; 25 times log-spaced 1e-3..1e3 s")
print("| cell (EA N, kappa N, alpha, P N) | exact inversion: worst rel. error | CPU ms | realized spectrum: worst "
      "rel. error (at t s) | local exponent at 1000 s: exact / inverted / spectrum |")
print("|---|---|---|---|---|")
for EA, kappa, alpha, P in [(1e-3, 100.0, 0.17, 1.0), (1.0, 2.0, 0.17, 1000.0), (0.05, 2.0, 0.5, 1000.0)]:
    lin = linearize_law(CELL, Springpot(EA=EA, kappa=kappa, alpha=alpha), P)
    exact = _uniform_springpot_creep(EA, kappa, alpha, T_G5, P)
    t0 = time.process_time()
    J = creep_compliance(lin, T_G5)
    cpu = 1e3 * (time.process_time() - t0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Js = creep_compliance(lin, T_G5, method="spectrum")
    e, es = np.abs(J / exact - 1), np.abs(Js / exact - 1)
    tt = np.array([900.0, 1000.0, 1100.0])
    ex3 = _uniform_springpot_creep(EA, kappa, alpha, tt, P)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sl = [np.gradient(np.log(y), np.log(tt))[1] for y in
              (ex3, creep_compliance(lin, tt), creep_compliance(lin, tt, method="spectrum"))]
    print(f"| ({EA:g}, {kappa:g}, {alpha:g}, {P:g}) | {e.max():.1e} | {cpu:.0f} | {es.max():.2g} "
          f"({T_G5[np.argmax(es)]:.3g}) | {sl[0]:.3f} / {sl[1]:.3f} / {sl[2]:.3f} |")
