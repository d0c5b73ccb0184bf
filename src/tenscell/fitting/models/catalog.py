"""The built-in mechanisms: one entry each (a new mechanism on an existing law is one entry here, and its name in
the command line's list, ``cli/fit.py``; a test checks they agree).

:data:`MECHANISMS` holds them by name; :func:`mechanism` looks one up (a :class:`~.mechanism.Mechanism` passes
through).
"""
from __future__ import annotations

from .mechanism import Field, Mechanism

__all__ = ["MECHANISMS", "mechanism", "mechanism_names", "ACTIVE_BETA", "PER_TENDON_VOIGT"]

#: TensionSpringpot's beta in ``springpot-tension+visc``: active axial stiffness at 1 rad/s per unit of tension over
#: length, about l/δ (tendon length l of micrometres, cross-bridges bearing force over δ of nanometres). The
#: bundled data bound it only from below (a profile with beta held: BIC −186 at 10, −217 at 30, −260 at 100, −267.0
#: to −267.5 from 300 to 3000; bench/proto_tension_springpot.py): above about 300 the geometric prestress stiffness
#: T/l is negligible beside the active one and only beta·s is determined, so it is held in that plateau
ACTIVE_BETA = 1000.0
#: the name of the paper's per-tendon Voigt fit (the existing :func:`tenscell.fitting.fit`), not a Mechanism
PER_TENDON_VOIGT = "voigt-per-tendon"



def _voigt(name, *, ea="family", c="family", ea_dist=None, c_dist=None, visc=False, desc="", multimodal=False):
    return Mechanism(name=name, law="Voigt", viscosity=visc, description=desc, multimodal=multimodal,
                     fields=(Field("EA", "stiffness", ea, ea_dist), Field("c", "damping", c, c_dist)))


def _builtin() -> dict[str, Mechanism]:
    mechs = [
        # multimodal: measured (issue 35) as the mechanisms whose fits to the bundled pair or the Fabry sweep end at a
        # worse RMS for some seed when the search stops at two agreeing starts instead of hopping on
        _voigt("voigt-compact", desc="Voigt tendons, stiffness and damping per family", multimodal=True),
        _voigt("voigt-compact+visc", visc=True, desc="Voigt tendons per family, cytoplasm viscosity"),
        _voigt("voigt-lognormal-damping", c="shared", c_dist="lognormal", multimodal=True,
               desc="Voigt tendons, stiffness per family, log-normal spread of damping"),
        _voigt("voigt-lognormal-stiffness", ea="shared", ea_dist="lognormal", c="shared",
               desc="Voigt tendons, log-normal spread of stiffness, one damping"),
        _voigt("voigt-trap-damping+visc", c="shared", c_dist="powerlaw", visc=True, multimodal=True,
               desc="Voigt tendons per family, trap-model (power-law) damping, cytoplasm viscosity"),
        Mechanism("maxwell", "Maxwell", (Field("EA", "stiffness"), Field("c", "damping")),
                  description="Maxwell tendons (filament turnover) per family"),
        Mechanism("maxwell+visc", "Maxwell", (Field("EA", "stiffness"), Field("c", "damping")), viscosity=True,
                  description="Maxwell tendons per family, cytoplasm viscosity"),
        Mechanism("sls", "StandardLinearSolid",
                  (Field("EA", "stiffness"), Field("EA_arm", "stiffness", "shared"), Field("c", "damping", "shared")),
                  description="standard linear solid tendons: spring per family, one arm"),
        Mechanism("sls-trap+visc", "StandardLinearSolid",
                  (Field("EA", "stiffness"), Field("EA_arm", "stiffness", "shared"),
                   Field("c", "damping", "shared", "powerlaw")), viscosity=True,
                  description="standard linear solid tendons, trap-model (power-law) arm damping, cytoplasm viscosity"),
        Mechanism("springpot", "Springpot",
                  (Field("EA", "stiffness"), Field("kappa", "coefficient"), Field("alpha", "exponent", "shared")),
                  description="springpot tendons per family, one exponent"),
        Mechanism("springpot+visc", "Springpot",
                  (Field("EA", "stiffness"), Field("kappa", "coefficient"), Field("alpha", "exponent", "shared")),
                  viscosity=True, description="springpot tendons per family, one exponent, cytoplasm viscosity"),
        Mechanism("springpot-tension+visc", "TensionSpringpot",
                  (Field("EA", "stiffness", "shared"), Field("kappa", "coefficient", "shared"),
                   Field("alpha", "exponent", "shared"), Field("beta", "ratio", "fixed", value=ACTIVE_BETA),
                   Field("alpha_T", "exponent", "shared")), viscosity=True,
                  description="passive springpot tendons plus an active springpot whose modulus is proportional to "
                              "the tension (beta = 1000), its own exponent, cytoplasm viscosity"),
        # issue 26: the prestress acts only through the paper's geometric stiffness P·Kp (no tension term in the law);
        # the two families' exponents mix with it through the structure's modes (bench/proto_geometric.py)
        Mechanism("springpot-alpha-family+visc", "Springpot",
                  (Field("EA", "stiffness", "shared"), Field("kappa", "coefficient"), Field("alpha", "exponent")),
                  viscosity=True, multimodal=True,
                  description="springpot tendons with a modulus and an exponent per family (actin, intermediate "
                              "filament), one spring EA, cytoplasm viscosity; the prestress acts through the geometric "
                              "prestress stiffness only"),
        # issue 26: a log-normal spread of the springpots' modulus over the tendons (one exponent): on the Xie et al.
        # medians it predicts 100-200 Hz from 1-30 Hz best of the prototypes (bench/proto_science_results.md, G3)
        Mechanism("springpot-lognormal-kappa+visc", "Springpot",
                  (Field("EA", "stiffness", "shared"), Field("kappa", "coefficient", "shared", "lognormal"),
                   Field("alpha", "exponent", "shared")),
                  viscosity=True,
                  description="springpot tendons with one exponent and a log-normal spread of their modulus over the "
                              "tendons, one spring EA, cytoplasm viscosity; the prestress acts through the geometric "
                              "prestress stiffness only"),
    ]
    return {m.name: m for m in mechs}


#: the built-in mechanisms by name (the new laws' mechanisms join when the laws exist: :func:`mechanism`)
MECHANISMS: dict[str, Mechanism] = _builtin()


def mechanism_names() -> tuple[str, ...]:
    """Every name ``fit(model=...)`` and ``tenscell fit --model`` accept, the per-tendon Voigt fit first."""
    return (PER_TENDON_VOIGT, *MECHANISMS)


def mechanism(spec) -> Mechanism:
    """A :class:`Mechanism` from its name (a key of :data:`MECHANISMS`) or itself."""
    if isinstance(spec, Mechanism):
        return spec
    if isinstance(spec, str) and spec in MECHANISMS:
        return MECHANISMS[spec]
    raise ValueError(f"model must be a Mechanism or one of {', '.join(MECHANISMS)}, got {spec!r}")
