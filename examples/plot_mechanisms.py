"""
Which mechanism explains the cells?
===================================

A *mechanism* is a tensegrity cell whose tendons share a few parameters that mean
something: here the recommended first model, ``tenscell.fitting.RECOMMENDED``. This
example fits it jointly to a prestress sweep and a frequency sweep, fits beside it its
*structure-free formula* (the same springs, power laws and viscosity added up with no
tensegrity between them) and the structural-damping power law of cell rheology, and
prints what the data determine and what they do not.

**The data are not raw measurements.** Both bundled data sets are points of published
laws: the prestress sweep of Stamenović et al. (2002) follows their straight lines at
0.1 Hz, the frequency sweep of Fabry et al. (2001) their power law plus a Newtonian
term. A model that fits them reproduces those laws; it is not thereby shown to be the
cells' mechanism. On the command line the same comparison over every mechanism is
``tenscell study mechanisms MY_FILES... --out DIR``.
"""
import matplotlib.pyplot as plt

import tenscell as tc
from tenscell.fitting import RECOMMENDED, fit
from tenscell.fitting.models import baseline_of
from tenscell.fitting.scores import compare_models
from tenscell.reports.fit import fit_markdown

data = [tc.bundled("stamenovic2002"), tc.bundled("fabry2001")]
for d in data:
    print(d.provenance.line())

# %%
# The mechanism, jointly on both data sets (two starts keep the example short; use more for a real fit).
result = fit(data, model=RECOMMENDED, starts=2, seed=0, progress=False)
print(result)

# %%
# Its structure-free formula on the same data: a tensegrity earns its place only where it does better.
formula = fit(data, model=baseline_of(result.spec), starts=2, seed=0, progress=False)
print(formula)

# %%
# Parameters with their standard errors (a factor ×/÷ where the error of a parameter fitted in its logarithm
# exceeds 50 %), "not determined" once per reason, and the correlations as lmfit lists them.
print(result.report().split("[[Residuals")[0])

# %%
# One table for the models: RMS, parameters, AIC and BIC on the same residuals. The power law has no prestress,
# so it cannot be fitted to the prestress sweep; it is compared on the frequency sweep alone below.
comparison = compare_models(result, structural=False, baselines=(formula,))
print(comparison)
sweep_only = compare_models(fit(data[1], model=RECOMMENDED, starts=2, seed=0, progress=False),
                            structural=fit(data[1], model="structural-damping+newtonian", starts=2, seed=0,
                                           progress=False))
print(sweep_only)
print(f"on the frequency sweep alone BIC prefers {sweep_only.best('bic')}: the law that generated those points")

# %%
# What the joint fit does not determine (nothing listed: every free parameter has a standard error within the
# bounds; a parameter held fixed by the mechanism is not measured by this fit at all).
undetermined = [p.name for p, (se, note) in zip(result.parameters, result.standard_errors) if se is None]
print("not determined:", ", ".join(undetermined) or "none")
held = [f"{f.law_parameter} = {f.value:g}" for f in result.spec.fields if f.layout == "fixed"]
print("held, not fitted:", ", ".join(held) or "none")

# %%
# Data (markers) against the fitted mechanism (lines), one panel per data set.
axes = result.plot()
plt.gcf().suptitle(f"{RECOMMENDED} fitted jointly to both bundled data sets")

# %%
# The full Markdown report (as ``tenscell fit --model`` writes it) holds the verdict, the identifiability, the
# baseline beside the fit and every point's error; its first lines:
print("\n".join(fit_markdown(result, formula).splitlines()[:12]))
