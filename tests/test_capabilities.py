"""What a model declares, every consumer asks (issue 35, item 1): the laws carry what a mechanism on them needs, the
Voigt cell's options and members are its own, and asking a model for what it does not have raises one error."""
import json

import numpy as np
import pytest

from tenscell import laws
from tenscell.fitting import CapabilityError, VoigtModel, fit, load_fit
from tenscell.fitting.models import get_model
from tenscell.fitting.models.formulas import TERMS, lumped_formula
from tenscell.fitting.models.mechanism import Field, Mechanism
from tenscell.io.data import bundled

QUICK = dict(starts=1, hops=0, max_nfev=5, seed=0, progress=False)


# ---- the laws carry what a mechanism on them needs ---------------------------------------------------------------
def test_every_law_with_parameters_declares_its_group_and_lumped_terms():
    carriers = [cls for cls in laws.LAWS.values() if cls.parameters]
    assert len(carriers) == 8  # every law but the composite of other laws
    for cls in carriers:
        assert cls.mechanism_group and cls.mechanism_group.startswith("mechanisms: "), cls.__name__
        assert cls.lumped_terms and set(cls.lumped_terms) <= set(TERMS), cls.__name__


def test_a_law_that_cannot_carry_a_mechanism_is_refused_when_it_is_built():
    with pytest.raises(ValueError, match="law CompositeLaw cannot carry a mechanism: it lacks per-tendon parameters"):
        Mechanism("composite", "CompositeLaw", ())
    with pytest.raises(ValueError, match="no law 'Kelvin'"):
        Mechanism("kelvin", "Kelvin", (Field("EA", "stiffness"),))


@pytest.mark.parametrize("law, fields", [
    ("PowerDashpot", (Field("EA", "stiffness"), Field("c", "damping", "shared"))),
    ("LinearSpring", (Field("k", "stiffness"), Field("c", "damping", "shared"))),
    ("StiffeningFilament", (Field("EA", "stiffness"), Field("c", "damping", "shared"), Field("b", "ratio", "fixed",
                                                                                          value=2.0))),
])
def test_a_mechanism_on_a_law_outside_the_catalog_needs_no_table(law, fields):
    """The four laws no catalog entry uses carry a mechanism from their class attributes alone: its help group, its
    lumped formula, its problem with an exact Jacobian."""
    mech = Mechanism(f"{law.lower()}-test", law, fields, viscosity=True)
    assert mech.group == laws.LAWS[law].mechanism_group
    formula = lumped_formula(mech)
    assert set(laws.LAWS[law].lumped_terms) <= set(formula.terms) and "aP" in formula.terms
    pb = mech.problem(bundled("fabry2001"))
    theta = pb.initial_guess(np.random.default_rng(0))
    J = pb.jacobian(theta)
    fd = pb.jacobian_fd(theta)
    assert np.all(np.isfinite(pb.residuals(theta)))
    np.testing.assert_allclose(J, fd, atol=1e-6 * np.abs(fd).max(), rtol=1e-4)


# ---- the Voigt cell's options are its own ------------------------------------------------------------------------
def test_the_voigt_options_on_fit_are_deprecated_and_still_work():
    data = bundled("fabry2001")
    new = fit(data, model=VoigtModel("uniform"), **QUICK)
    with pytest.warns(DeprecationWarning, match=r"tenscell\.fit\(tendons=\) is deprecated.*model=VoigtModel"):
        old = fit(data, tendons="uniform", **QUICK)
    assert old.spec == new.spec and old.rms_log10_error == new.rms_log10_error
    with pytest.warns(DeprecationWarning), pytest.raises(CapabilityError, match="tendons: option"):
        fit(data, model="springpot", tendons="per-family", **QUICK)
    with pytest.raises(TypeError, match="tendon"):
        fit(data, tendon="uniform", **QUICK)


def test_voigt_members_moved_to_the_fitted_cell():
    data = bundled("fabry2001")
    r = fit(data, model=VoigtModel("per-family", "per-family"), **QUICK)
    model = r.model
    assert (model.tendons, model.damping) == ("per-family", "per-family")
    for name in ("tendons", "damping", "EA", "c", "L"):
        with pytest.warns(DeprecationWarning, match=rf"tenscell\.FitResult\.{name} is deprecated .*: use result\.model"):
            old = getattr(r, name)
        np.testing.assert_array_equal(old, getattr(model, name))
    with pytest.warns(DeprecationWarning, match=r"prestress_activity\(result\)"):
        assert r.prestress is not None
    mech = fit(data, model="springpot+visc", **QUICK)
    for name in ("tendons", "damping", "EA", "c", "L", "prestress"):
        with pytest.raises(CapabilityError, match=rf"FitResult\.{name} is a member of the Voigt cell's fit"):
            getattr(mech, name)


def test_the_fitted_cell_records_its_layout_and_old_files_still_load(tmp_path):
    r = fit(bundled("fabry2001"), model=VoigtModel("uniform"), **QUICK)
    doc = r.to_dict()
    assert doc["model"]["tendons"] == "uniform" and doc["model"]["damping"] == "uniform"
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    assert load_fit(path).spec == VoigtModel("uniform")
    for key in ("tendons", "damping"):  # a fit.json written before the layout was recorded
        del doc["model"][key]
    path.write_text(json.dumps(doc))
    old = load_fit(path)
    assert old.tendons is None and old.spec == VoigtModel()


def test_what_a_model_does_not_have_raises_one_error():
    formula = fit(bundled("fabry2001"), model="structural-damping", **QUICK).model
    for ask in (lambda: formula.tendon_law(), lambda: formula.linear(), lambda: formula.voigt_tendons(1.0),
                lambda: formula.ensemble_problem(4), lambda: formula.evaluation()):
        with pytest.raises(CapabilityError):
            ask()
    assert formula.cell is None and not formula.capabilities.structural
    assert get_model("springpot+visc").with_options() is get_model("springpot+visc")


def test_the_catalog_marks_the_multimodal_mechanisms_and_old_fit_files_read_false():
    from tenscell.fitting.models import RECOMMENDED
    from tenscell.fitting.models.base import model_from_dict

    assert get_model(RECOMMENDED).capabilities.multimodal  # reached its best from 1 start in 10 (catalog)
    assert not get_model("springpot-tension+visc").capabilities.multimodal  # every start: one optimum
    doc = get_model(RECOMMENDED).to_dict()
    assert doc["multimodal"] is True
    del doc["multimodal"]  # a fit.json written before the field existed
    assert model_from_dict(doc).multimodal is False
