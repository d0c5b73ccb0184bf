"""The Markdown report of the compactness study, rendered only from its result fields."""
from __future__ import annotations

from ..studies.compactness import CompactnessStudy
from ._format import num, table

__all__ = ["compactness_markdown"]

#: the spread of the paper's own Fig. 5 fit, which it calls unrealistic (decades)
PAPER_SPREAD_DECADES = 8.0


def compactness_markdown(study: CompactnessStudy, title: str | None = None) -> str:
    """The front (best RMS per bound), the answer, and what the study does not show."""
    names = ", ".join(f"`{s}`" for s in study.sources)
    out = [f"# {title or 'Compactness: how narrow can the stiffness distribution be?'}", "",
           f"Data: {names}. Model: {study.fits[0].cell.describe()}; stiffness {study.fits[0].model.tendons}, damping "
           f"{study.fits[0].model.damping}. For each bound D on log10(max EA / min EA) the model was fitted with the "
           "spread constrained to at most D decades (tolerance "
           f"{num(study.tolerance)} decades RMS{' on every data set' if len(study.sources) > 1 else ''}).", ""]
    knee = study.knee
    if knee is None:
        out.append(f"**No bound from {num(study.decades.min())} to {num(study.decades.max())} decades reached the "
                   "tolerance.**")
    else:
        spread = study.spread[study.decades == knee][0]
        narrower = knee < PAPER_SPREAD_DECADES
        out.append(f"**The narrowest bound within the tolerance is {num(knee)} decades** (fitted spread "
                   f"{spread:.2f} decades, RMS {num(study.rms[study.decades == knee][0], 3)}): "
                   + (f"narrower than the {num(PAPER_SPREAD_DECADES)} decades of the paper's fit, so a more compact "
                      "distribution does fit these data." if narrower else
                      f"not narrower than the {num(PAPER_SPREAD_DECADES)} decades of the paper's fit."))
    starts = study.fits[0].starts
    out += ["", table(("bound D (decades)", "best RMS log10 error", "its spread (decades)", "within tolerance",
                       "this bound's own search"),
                      [(num(d), num(r, 3), f"{s:.2f}", "yes" if ok else "no", num(q, 3))
                       for d, r, s, ok, q in study.rows()]),
            "The best RMS at a bound is the best of the searches at that bound and every narrower one (their fits "
            "satisfy the wider bound too). Each search stops once it is well inside the tolerance (at a fifth of "
            "it) or has polished as long as reaching the tolerance took, so RMS values well below the tolerance "
            "are where a search stopped, not the best possible. The front is what searches of this effort "
            f"found ({starts} starts per bound plus a warm start from the next wider bound): a bound that did not "
            "reach the tolerance here might with more effort; one that did shows that such a compact "
            "distribution fits.", ""]
    generated = [d.source for d in study.fits[0].datasets if any("generated" in c.lower() for c in d.comments)]
    if generated:
        out += ["Generated, not measured: " + ", ".join(f"`{s}`" for s in generated) + " (their own comments say "
                "they were generated from published fit laws, not raw measurements).", ""]
    return "\n".join(out)
