"""
Read an instrument's export
===========================

Rheometers write their own text layouts. ``tenscell.read_data`` recognises TA TRIOS
(``[step]`` text exports, LIMS exports, the plain ``Variables``/``Data point`` layout)
and Anton Paar RheoCompass exports, converts every unit it finds in the file, records
what it read (the data's *provenance*) and refuses, in one line saying why, what it
should not fit: a step at one frequency, a row count that contradicts the header, a
value many decades off the rest of its column.

The two files used here are tenscell's own test fixtures in ``tests/data`` (in an
instrument's layout, but **written from a structural-damping law with 2 % scatter**, as
their sample notes say: they are not recordings).
"""
from pathlib import Path

import matplotlib.pyplot as plt

import tenscell as tc
from tenscell.fitting import RECOMMENDED, fit

HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
FIXTURES = HERE.parent / "tests" / "data"

# %%
# A TRIOS LIMS export with three frequency sweeps, at 37, 25 and 15 °C. A step is chosen by its temperature
# (``--temperature 25`` on the command line), its name or its number; moduli in MPa become Pa.
trios = FIXTURES / "trios_lims_temperature_steps.txt"
sweeps = {T: tc.read_data(trios, temperature=T) for T in (37, 25, 15)}
for d in sweeps.values():
    print(d.provenance.line())

# %%
# A RheoCompass export: interval 1 is an amplitude sweep at one frequency, which a frequency-domain model cannot
# be fitted to; asked for it, the reader says so (``accept="one-frequency"`` reads it anyway).
rheocompass = FIXTURES / "rheocompass_frequency_sweep.txt"
try:
    tc.read_data(rheocompass, step=1)
except tc.io.DataError as err:
    print("refused:", err)
sweep = tc.read_data(rheocompass)  # the frequency sweep (interval 2), chosen because it is the only one that fits
print(sweep.provenance.line())

# %%
# The three temperatures, as read.
fig, ax = plt.subplots()
for T, d in sweeps.items():
    ax.loglog(d.frequency_hz, d.G_storage, "o-", label=f"G' at {T} °C")
    ax.loglog(d.frequency_hz, d.G_loss, "s--", label=f"G'' at {T} °C")
ax.set_xlabel("frequency (Hz)")
ax.set_ylabel("modulus (Pa)")
ax.legend(fontsize="small")

# %%
# Fit the recommended mechanism and the structural-damping power law to each temperature. The fixtures were
# written from that power law with one exponent at every temperature (only its modulus scale changes), so the law
# fits them by construction and its fitted exponents should agree within their errors.
for T, d in sweeps.items():
    mech = fit(d, model=RECOMMENDED, starts=2, seed=0, progress=False)
    law = fit(d, model="structural-damping+newtonian", starts=2, seed=0, progress=False)
    bic_m, bic_l = mech.information_criteria()[1], law.information_criteria()[1]
    se = dict(zip((p.name for p in law.parameters), law.standard_errors))["alpha"][0]
    print(f"{T} °C: {RECOMMENDED} rms {mech.rms_log10_error:.4f} ({mech.verdict}), BIC {bic_m:.1f}; power law "
          f"rms {law.rms_log10_error:.4f}, BIC {bic_l:.1f}, alpha = {law.value('alpha'):.3f} +/- {se:.3f}")

# %%
# What was read travels with the fit: ``fit.json`` (``provenance``) and the report name the file, the step, the
# temperature and every unit conversion.
print(mech.to_dict()["provenance"][0]["text"])
