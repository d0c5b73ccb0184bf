"""Mechanisms: frozen, few-parameter specifications of what sets a cell's moduli, each one fittable.

A :class:`Mechanism` names a tendon law (a class of :mod:`tenscell.laws` with a
dynamic tangent ``complex_stiffness``) and says how each of the law's
parameters is laid out over the tendons (:class:`Field`): one value per
family (actin / intermediate filament), one value shared by every tendon, a
fixed value, or drawn from a named distribution
(:mod:`tenscell.fitting.heterogeneity`) whose scale is per family or shared
and whose shape (spread in decades, or a trap-model exponent) is one more
parameter. Optionally a cytoplasm viscosity η (Pa·s) acts in parallel with the
structure. The prestress parameters come from the data exactly as in the
per-tendon fit (:mod:`tenscell.fitting.problem`).

The per-tendon stiffnesses, damping and prestress of a mechanism are those of
the reference cell (strut length ``L_ref``, 1 m for the paper cell): the
strut length is not a parameter, because ``(P, EA, c, L) -> (λ²P, λ²EA, λc,
λL)`` leaves the moduli unchanged; a mechanism has no gauge.

:data:`MECHANISMS` holds the built-in ones by name; :func:`mechanism` looks
one up (a :class:`Mechanism` passes through).
"""
from __future__ import annotations

from dataclasses import dataclass

from .heterogeneity import DISTRIBUTIONS

__all__ = ["Field", "Mechanism", "MECHANISMS", "mechanism", "KINDS", "PER_TENDON_VOIGT", "ACTIVE_BETA"]

#: what a parameter kind is, for bounds and starts: (unit, scales G when all scalable ones scale together)
KINDS = {
    "stiffness": ("N", True),
    "damping": ("N·s/m", True),
    "coefficient": ("N (at 1 rad/s)", True),
    "time": ("s", False),
    "exponent": ("", False),
    "decades": ("decades", False),
    "tail": ("", False),
    "viscosity": ("Pa·s", True),
    "ratio": ("", False),  # a dimensionless modulus per unit tension (TensionSpringpot's beta)
}
#: the layouts of a law parameter over the tendons
LAYOUTS = ("family", "shared", "fixed")
#: TensionSpringpot's beta in ``springpot-tension+visc``: active axial stiffness at 1 rad/s per unit of tension over
#: length, about l/δ (tendon length l of micrometres, cross-bridges bearing force over δ of nanometres). The
#: bundled data bound it only from below (a profile with beta held: BIC −186 at 10, −217 at 30, −260 at 100, −267.0
#: to −267.5 from 300 to 3000; bench/proto_tension_springpot.py): above about 300 the geometric prestress stiffness
#: T/l is negligible beside the active one and only beta·s is determined, so it is held in that plateau
ACTIVE_BETA = 1000.0
#: the name of the paper's per-tendon Voigt fit (the existing :func:`tenscell.fitting.fit`), not a Mechanism
PER_TENDON_VOIGT = "voigt-per-tendon"


@dataclass(frozen=True)
class Field:
    """How one law parameter is laid out over the tendons.

    Attributes
    ----------
    law_parameter : str
        The parameter's name in the law (e.g. ``"EA"``, ``"c"``, ``"alpha"``).
    kind : str
        A key of :data:`KINDS` (bounds and starts).
    layout : {"family", "shared", "fixed"}
        One fitted value per family, one for all tendons, or ``value`` for all.
    distribution : str or None
        A key of :data:`~tenscell.fitting.heterogeneity.DISTRIBUTIONS`: the
        layout's value(s) are the distribution's scale and one more parameter
        (its shape, shared by the families) spreads the tendons.
    value : float or None
        The value of a fixed parameter (SI units).
    """

    law_parameter: str
    kind: str
    layout: str = "family"
    distribution: str | None = None
    value: float | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Field {self.law_parameter!r}: kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.layout not in LAYOUTS:
            raise ValueError(f"Field {self.law_parameter!r}: layout must be one of {', '.join(LAYOUTS)}, "
                             f"got {self.layout!r}")
        if (self.layout == "fixed") != (self.value is not None):
            raise ValueError(f"Field {self.law_parameter!r}: a value is given exactly for the fixed layout")
        if self.distribution is not None and self.distribution not in DISTRIBUTIONS:
            raise ValueError(f"Field {self.law_parameter!r}: distribution must be one of "
                             f"{', '.join(DISTRIBUTIONS)}, got {self.distribution!r}")
        if self.distribution is not None and self.layout == "fixed":
            raise ValueError(f"Field {self.law_parameter!r}: a fixed parameter has no distribution")


@dataclass(frozen=True)
class Mechanism:
    """A fittable mechanism: a tendon law, its parameters' layout, a cytoplasm, the heterogeneity's sampling.

    Attributes
    ----------
    name : str
    law : str
        Class name in :mod:`tenscell.laws` (``"Voigt"``, ...).
    fields : tuple of Field
        One per parameter of the law, in any order.
    viscosity : bool
        A cytoplasm viscosity η (Pa·s) in parallel with the structure.
    assignments : int
        K, the number of stratified assignments the moduli are averaged over
        (used only when a field has a distribution).
    seed : int
        Seed of the assignments.
    description : str
    """

    name: str
    law: str
    fields: tuple
    viscosity: bool = False
    assignments: int = 8
    seed: int = 0
    description: str = ""

    def __post_init__(self):
        names = [f.law_parameter for f in self.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"mechanism {self.name!r}: a law parameter is laid out twice")
        if isinstance(self.assignments, bool) or not isinstance(self.assignments, int) or self.assignments < 1:
            raise ValueError(f"mechanism {self.name!r}: assignments must be an integer >= 1")

    @property
    def heterogeneous(self) -> bool:
        """Whether a field is drawn from a distribution (the moduli are then averaged over K assignments)."""
        return any(f.distribution is not None for f in self.fields)

    @property
    def K(self) -> int:
        """Assignments actually used: :attr:`assignments` if heterogeneous, else 1."""
        return self.assignments if self.heterogeneous else 1


def _voigt(name, *, ea="family", c="family", ea_dist=None, c_dist=None, visc=False, desc=""):
    return Mechanism(name=name, law="Voigt", viscosity=visc, description=desc,
                     fields=(Field("EA", "stiffness", ea, ea_dist), Field("c", "damping", c, c_dist)))


def _builtin() -> dict[str, Mechanism]:
    mechs = [
        _voigt("voigt-compact", desc="Voigt tendons, stiffness and damping per family"),
        _voigt("voigt-compact+visc", visc=True, desc="Voigt tendons per family, cytoplasm viscosity"),
        _voigt("voigt-lognormal-damping", c="shared", c_dist="lognormal",
               desc="Voigt tendons, stiffness per family, log-normal spread of damping"),
        _voigt("voigt-lognormal-stiffness", ea="shared", ea_dist="lognormal", c="shared",
               desc="Voigt tendons, log-normal spread of stiffness, one damping"),
        _voigt("voigt-trap-damping+visc", c="shared", c_dist="powerlaw", visc=True,
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
                  viscosity=True,
                  description="springpot tendons with a modulus and an exponent per family (actin, intermediate "
                              "filament), one spring EA, cytoplasm viscosity; the prestress acts through the geometric "
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
