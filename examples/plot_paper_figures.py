"""
The paper's figures: the cell and its moduli
=============================================

Sultan, Stamenović & Ingber (2004) model an adherent cell as a 6-strut tensegrity
anchored to its substrate (their Fig. 1) and show how its storage and loss moduli
depend on the prestress (Fig. 2) and on the frequency (Fig. 3). Here the three
figures are drawn from :func:`tenscell.paper_cell` and
:func:`tenscell.frequency_response`.
"""
import matplotlib.pyplot as plt
import numpy as np

import tenscell as tc
from tenscell import plotting

cell = tc.paper_cell()  # alpha = 0, delta = 50°, strut length L = 1 m
print(cell)

# %%
# Fig. 1: the cell. Struts (microtubules) grey, actin black, intermediate
# filaments red; the three anchors are blue triangles, the load a green arrow.
cell.plot(title="The paper's cell (Fig. 1 colours)")

# %%
# Fig. 2: G' and G'' against the prestress P (N; the paper calls it Pa) at a few
# frequencies, with unit tendon stiffness EA (N) and damping c (N·s/m).
P = np.linspace(500.0, 4500.0, 21)
fig2 = tc.frequency_response(cell, [0.01, 0.1, 1.0, 10.0, 100.0], P, EA=1.0, c=1.0)
plotting.fig2_prestress(fig2)

# %%
# Fig. 3: G' and G'' against frequency at four prestresses. At low frequency G'
# grows in proportion to P (the prestress carries the stiffness); at high
# frequency the damping of the tendons takes over.
fig3 = tc.frequency_response(cell, np.logspace(-2, 3, 61), [500.0, 1000.0, 2000.0, 4500.0])
plotting.fig3_frequency(fig3)
fig3.to_dataframe().head()

# %%
# The same response drawn on axes of your own, e.g. beside the loss tangent.
fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(11, 3.4), layout="constrained")
fig3.plot(axes=[a1, a2], legend=False)
for P_i, tan_d in zip(fig3.prestress, fig3.loss_tangent):
    a3.semilogx(fig3.frequency_hz, tan_d, label=f"P = {P_i:g} N")
a3.set(xlabel="frequency f (Hz)", ylabel="loss tangent G″/G′")
a3.legend()
plt.show()
