"""
Fit a lab's data
================

Measured moduli rarely come in tenscell's own column names and units. This example
reads a frequency sweep exported with angular frequency in rad/s and moduli in kPa,
converts it explicitly with a :class:`tenscell.io.ColumnMap`, and fits the paper's cell
to it (tendon stiffnesses, damping, prestress and strut length).

The numbers are the airway smooth muscle data of Fabry et al. (2001) shipped with
tenscell, written out here as a lab's file would be.
"""
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

import tenscell as tc
from tenscell.fitting import VoigtModel

ref = tc.bundled("fabry2001")
export = pd.DataFrame({"omega [rad/s]": 2 * np.pi * ref.frequency_hz,
                       "G' [kPa]": ref.G_storage / 1e3,
                       "G'' [kPa]": ref.G_loss / 1e3})
path = Path(tempfile.mkdtemp()) / "hasm_sweep.csv"
export.to_csv(path, index=False)
print(path.read_text().splitlines()[:3])

# %%
# Read it: the map names the columns; the units come from the headers (a unit the
# file does not state must be given in the map, e.g. ``modulus_unit="kPa"``).
data = tc.read_table(path, tc.io.ColumnMap(frequency="omega", storage="G'", loss="G''"))
print(data)
print(data.comments[-1])

# %%
# Headers that say what they hold need no map at all: ``tc.read_data`` recognises
# ``Angular Frequency``, ``Storage Modulus``, ``G'``, ``time (s)``, ``J(t) (1/Pa)``... and
# instrument exports (TA TRIOS, Anton Paar RheoCompass); units still come from the file.
lab = export.rename(columns={"omega [rad/s]": "Angular Frequency [rad/s]", "G' [kPa]": "Storage Modulus [kPa]",
                             "G'' [kPa]": "Loss Modulus [kPa]"})
lab.to_csv(path.with_name("lab_sweep.tsv"), sep="\t", index=False)
same = tc.read_data(path.with_name("lab_sweep.tsv"))
print(np.allclose(same.G_storage, data.G_storage))

# %%
# Fit, one stiffness per tendon as in the paper (one start keeps the example short; use several for a real fit).
result = tc.fit(data, model=VoigtModel(tendons="per-tendon"), starts=1, seed=0, progress=False)
print(f"rms log10 error {result.rms_log10_error:.4f} decades; converged: {result.converged}")

print(result)

# %%
# Data (circles) against the fitted model (lines).
ax = result.plot()
ax.set_title("paper cell fitted to HASM data")

# %%
# The fitted parameters as a table, each with its standard error (or why it has none).
result.parameters_dataframe()[["name", "value", "stderr", "stderr_percent", "unit", "stderr_note"]]
