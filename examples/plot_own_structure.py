"""
Your own structure
==================

Any tensegrity can be written to and read from a JSON structure file
(``docs/structure-format.md``). Here the paper's cell is saved, edited by hand —
the nucleus raised by 0.1 m and the paper's equal-tension requirement on the
intermediate filaments dropped — and read back. :func:`tenscell.model.equilibrate`
finds the new self-stress; the moduli of the two cells are compared.
"""
import json
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import tenscell as tc

folder = Path(tempfile.mkdtemp())
paper = tc.paper_cell()
tc.io.save_structure(folder / "paper.json", paper.structure, EA=1.0, c=1.0, description="the paper's cell")

doc = json.loads((folder / "paper.json").read_text())
print(doc["units"], doc["nodes"][-1])

# %%
# Edit the file as you would in a text editor: move the nucleus node ``N`` up and
# let the intermediate filaments carry unequal tensions.
doc["name"] = "nucleus raised"
doc["nodes"][-1]["xyz"][2] += 0.1
del doc["equal_tension_groups"]
(folder / "raised.json").write_text(json.dumps(doc, indent=1))

raised = tc.model.equilibrate(tc.load_structure(folder / "raised.json"))
print(raised)

# %%
# The two cells side by side.
fig = plt.figure(figsize=(9, 4.2), layout="constrained")
paper.plot(ax=fig.add_subplot(1, 2, 1, projection="3d"), title="paper cell")
raised.plot(ax=fig.add_subplot(1, 2, 2, projection="3d"), title="nucleus raised by 0.1 m")

# %%
# Moduli at P = 1000 N: the raised nucleus stiffens the cell slightly.
f = np.logspace(-2, 3, 61)
fig, axes = plt.subplots(1, 2, figsize=(8, 3.4), layout="constrained")
for cell, ls in ((paper, "-"), (raised, "--")):
    tc.frequency_response(cell, f, 1000.0).plot(axes=axes, ls=ls, legend=False)
axes[0].legend(["paper cell", "nucleus raised"])
tc.linearize(raised, P=1000.0).to_dataframe().head()
