"""
A population of measured cells
==============================

Xie et al. (Soft Matter 2024) measured G′ and G″ of single adherent cells by AFM at 1–200
Hz: 59 MCF-10A and 46 MDA-MB-436 cells. This example fits a sample of them, one cell at a
time, with the paper's cell (one stiffness per family, one damping, the strut length held)
through ``tenscell.population.fit_population`` and compares the two lines.

Those data carry **no licence**, so tenscell does not ship them: the example reads them
from ``../shared/data/real-cells/xie2024_population`` beside a clone of the repository
where that folder exists, and otherwise says so and stops. Read
``real-cells/PROVENANCE.md`` before trusting a number: the authors kept per cell the
curve nearest its median Hertz modulus among curves whose moduli rise with frequency (a
selection bias), the 1 Hz values are the least reliable, and part of the rise of G″ at
100–200 Hz may be hydrodynamic drag, which no correction removed.
"""
from pathlib import Path

import tenscell as tc
from tenscell.population import PopulationFitOptions, fit_population, read_sources

HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
CELLS = HERE.parent.parent / "shared" / "data" / "real-cells" / "xie2024_population"
available = CELLS.is_dir()
if not available:
    print(f"skipped: {CELLS} is absent (the measured cells are read from ../shared/data beside a clone, never "
          "shipped with tenscell: their repository states no licence)")

# %%
# Every cell file of both lines (one folder per line is the condition), then every tenth cell of each line, so that
# the example stays short; ``tenscell fit-population DIR --out fits/`` fits them all.
if available:
    sources = read_sources(CELLS)
    sample = [s for line in sorted({s.condition for s in sources})
              for s in [s for s in sources if s.condition == line][::10]]
    print(f"{len(sources)} cells found; fitting {len(sample)}")

# %%
# One fit per cell (two starts each, in this process). The strut length is held, so that the cells' stiffnesses
# are comparable; the prestress is fitted, as no cell states it.
if available:
    result = fit_population(sample, options=PopulationFitOptions(starts=2, hops=0), seed=0, workers=0,
                            progress=False)
    print(result)

# %%
# Per line: medians and interquartile ranges over the cells. The spread across cells includes each fit's own
# uncertainty; no test of significance is made. Read the RMS first: the tolerance is 0.02 decades.
if available:
    summary = result.summary()
    shown = summary[summary["quantity"].isin(["rms_log10_error", "G_storage_ref_Pa", "storage_slope", "P_N"])]
    print(shown[["condition", "quantity", "n_fitted", "n_converged", "median", "q25", "q75"]].to_string(index=False))
    ok = result.table[result.table["status"] == "ok"]
    print(f"{int(ok['converged'].sum())} of {len(ok)} cells reached the tolerance; median RMS "
          f"{ok['rms_log10_error'].median():.3f} decades: where that is far above the tolerance, the per-family "
          "Voigt cell does not describe these cells, and its parameters are not measurements of them")

# %%
# The fitted parameters' distributions, per line.
if available:
    result.plot()

# %%
# The same question for a mechanism, on each line's median cell (medians over the cells whose moduli are positive
# at all six frequencies; the sd columns are bootstrap errors of the median, not the spread between cells), beside
# the structural-damping power law with no tensegrity in it.
if available:
    from tenscell.fitting import RECOMMENDED, fit

    for line in ("MCF-10A", "MDA-MB-436"):
        median = tc.read_data(CELLS.parent / f"xie2024_median_{line}.csv")
        mech = fit(median, model=RECOMMENDED, starts=2, seed=0, progress=False)
        law = fit(median, model="structural-damping+newtonian", starts=2, seed=0, progress=False)
        print(f"{line}: {RECOMMENDED} RMS {mech.rms_log10_error:.3f} decades ({mech.verdict}), BIC "
              f"{mech.information_criteria()[1]:.1f}; power law RMS {law.rms_log10_error:.3f} ({law.verdict}), BIC "
              f"{law.information_criteria()[1]:.1f}")
