"""Every model kind through every public member of FitResult and a fit.json round trip (issue 35, item 5c).

One fit of each kind — the Voigt cell per tendon, per family and uniform, a mechanism, a mechanism with a distributed
tendon property, a structure-free formula, a population — with a tiny search budget (one start, no hops, a few
evaluations: what is checked is what each member answers, not the fit's quality). Every public member of
:class:`tenscell.fitting.FitResult` (found by introspection, so a new member is checked without a line here) either
works or raises the one documented error of a model without it, :class:`tenscell.fitting.CapabilityError`; the
Voigt cell's moved members warn with their new home. The fit.json each writes loads back into a fitted model with the
same moduli.
"""
import dataclasses
import inspect
import json
import math
import warnings

import matplotlib

matplotlib.use("Agg")  # noqa: E402 - the plot member draws on the headless renderer

import matplotlib.pyplot as plt
import numpy as np
import pytest

from tenscell.fitting import CapabilityError, FitResult, Population, VoigtModel, fit, load_fit
from tenscell.io.data import RheologyData, bundled
from tenscell.io.outputs import write_json

TINY = dict(starts=1, hops=0, max_nfev=3, seed=0, progress=False)
F = np.array([0.1, 1.0, 10.0])
#: the members that take arguments, with the arguments a check gives them
ARGUMENTS = {"value": lambda r: (r.parameters[0].name,), "moduli": lambda r: (F,),
             # a prestress sweep spans several prestresses: its model P needs prestress_pa (documented); the
             # member is asked of the first data set measured at one
             "prestress_model": lambda r: (None, r.single_prestress_dataset())}
#: the members that only a fit of the Voigt cell has (moved to its fitted cell: deprecated on the result)
VOIGT_ONLY = ("tendons", "damping", "EA", "c", "L", "prestress")
#: the members that only a model with a cell has (a structure-free formula raises CapabilityError)
CELL_ONLY = ("linear", "predicted_creep")


def _population_cells():
    base = bundled("fabry2001")
    return [RheologyData(frequency_hz=base.frequency_hz, G_storage=base.G_storage * k, G_loss=base.G_loss * k,
                         source=f"cell {i}") for i, k in enumerate((0.5, 1.0, 2.0))]


KINDS = {
    "voigt per tendon": (VoigtModel("per-tendon"), lambda: bundled("fabry2001")),
    "voigt per family": (VoigtModel("per-family", "per-family"), lambda: bundled("fabry2001")),
    "voigt uniform": (VoigtModel("uniform"), lambda: [bundled("stamenovic2002"),
                                                      bundled("fabry2001").with_prestress(1000.0)]),
    "mechanism": ("springpot-alpha-family+visc", lambda: [bundled("stamenovic2002"),
                                                          bundled("fabry2001").with_prestress(1000.0)]),
    "heterogeneous mechanism": ("voigt-lognormal-damping", lambda: bundled("fabry2001")),
    "formula": ("structural-damping+newtonian", lambda: bundled("fabry2001")),
    "population": (Population("structural-damping+newtonian", per_cell=("G0",)), _population_cells),
}


def _public_members() -> list[str]:
    names = {n for n in dir(FitResult) if not n.startswith("_")}
    names |= {f.name for f in dataclasses.fields(FitResult)}
    return sorted(names)


def _call(result, name):
    """The member ``name`` of ``result``: its value, or its call with the check's arguments."""
    static = inspect.getattr_static(FitResult, name, None)
    if not callable(static) or isinstance(static, (property,)):
        return getattr(result, name)
    if name == "compute_profile":
        return result.compute_profile(parameters=())  # the member, not a profile's refits
    if name == "plot":
        ax = result.plot()
        plt.close("all")
        return ax
    args = ARGUMENTS.get(name, lambda r: ())(result)
    return getattr(result, name)(*args)


@pytest.fixture(scope="module", params=sorted(KINDS))
def kind(request):
    spec, data = KINDS[request.param]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a 3-evaluation fit may sit anywhere
        return request.param, fit(data(), model=spec, **TINY)


def test_every_public_member_works_or_raises_the_documented_error(kind):
    name, r = kind
    voigt = r.spec.capabilities.voigt_options
    for member in _public_members():
        if member in VOIGT_ONLY and voigt:
            with pytest.warns(DeprecationWarning, match=rf"tenscell\.FitResult\.{member} is deprecated"):
                _call(r, member)
            continue
        if member in VOIGT_ONLY or (member in CELL_ONLY and not r.spec.capabilities.structural):
            with pytest.raises(CapabilityError):
                _call(r, member)
            continue
        if member == "data" and r.joint:
            with pytest.raises(ValueError, match="joint fit"):  # documented: a joint fit has .datasets
                _call(r, member)
            continue
        try:
            _call(r, member)
        except Exception as err:  # noqa: BLE001 - the message names the member and the kind
            pytest.fail(f"{name}: FitResult.{member} raised {type(err).__name__}: {err}")


def test_fit_json_round_trips(kind, tmp_path):
    name, r = kind
    doc = r.to_dict()
    path = tmp_path / "fit.json"
    write_json(path, doc)
    back = load_fit(path)
    assert json.loads(path.read_text())["model_name"] == r.spec.name
    assert type(back) is type(r.model) and back.spec == r.model.spec, name
    P = back.default_prestress_pa
    a, b = r.model.moduli(F, P), back.moduli(F, P)
    for x, y in zip(a, b):
        np.testing.assert_allclose(y, x, rtol=1e-12)
    assert math.isfinite(doc["rms_log10_error"])
