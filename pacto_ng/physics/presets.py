"""Material presets: a named material with published fits of the rubber laws of
:mod:`~pacto_ng.physics.hyperelastic`, selected with ``--set material=NAME`` (docs/guide.md,
"Materials").

A :class:`Fit` holds the coefficients *as published* (Pa, Abaqus convention: Mooney–Rivlin
``(C10, C01)``, Yeoh ``(C10, C20, C30)``, Ogden ``((μ_1, α_1), (μ_2, α_2), ...)`` with
``W = Σ 2 μ_p/α_p² (Σ λ̄^α_p - 3)``) and its source (authors, year, journal, table).  From it
come the small-strain shear modulus ``μ0`` and the dimensionless *shape* the energies take
(coefficients / ``μ0``).  A :class:`Preset` is a material: one fit or more (the first is the
preset's own law) and the Poisson ratio it is used with.

The rule (:func:`apply`, called by :class:`~pacto_ng.physics.energy.MaterialSettings`):

* the preset sets the hyperelastic law and its coefficients: ``--model wang`` interpolates the
  preset's law with the linear energy, ``--model mooney_rivlin|yeoh|ogden`` uses the preset's fit
  of that law (an error if it has none);
* it sets ``E1 = 2 μ0 (1 + ν)`` (``μ0`` of the fit in use; of the preset's own law for
  ``linear``, ``gnl``, ``neohookean`` and ``wang``), so that ``--model linear`` has the
  preset's small-strain stiffness, and scales ``E0`` with it (the case's ratio ``E0/E1`` is
  kept);
* ``ν`` is the preset's (:attr:`Preset.nu`) unless ``--set nu=`` gave another value: a preset
  replaces ``nu`` only while it equals ``nu_case``, the ν the case set (recorded while no preset
  is selected).  A ``--set nu=`` equal to the case's own ν cannot be told from it.

Shipped (:data:`SHIPPED`): Ecoflex 00-30, Dragon Skin 30 (Smooth-On cast silicones) and Elastic
50A (Formlabs SLA elastomer), Yeoh fits, each with its source.  A case file (or any script)
registers more with :func:`register`, stating its source; ``--set material=NAME`` then selects
it.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import fsum

from .hyperelastic import LAWS, Law

#: the Poisson ratio of a preset unless it states its own.  Silicones are nearly incompressible
#: (ν ≈ 0.49-0.4999), but the displacement formulation locks as ν -> 0.5: docs/studies.md,
#: "Volumetric locking": Q1 quadrilaterals bend 4.9 % too little at ν = 0.45 and 19 % at 0.49;
#: its stability map (pa-inverter, 2026-12-02): Neo-Hookean completes 3e6 Pa at ν = 0.3 and
#: 0.45 but 1e6 Pa at 0.49, and Wang 1e7 Pa at 0.45 but fails by inversion in the locked solid
#: after 3e6 Pa at 0.49.  0.45 (K = 9.7 μ0) is the most nearly incompressible value measured
#: without that loss, and the value from which ``formulation=auto`` takes the mixed
#: formulation (physics/mixed.py, NU_MIXED); ``--set nu=0.49`` asks for more.
DEFAULT_NU = 0.45

#: the shape of each law without a preset: the isochoric Neo-Hookean (documented default)
DEFAULT_SHAPES = {"mooney_rivlin": (0.5, 0.0), "yeoh": (0.5, 0.0, 0.0), "ogden": ((1.0, 2.0),)}


@dataclass(frozen=True)
class Fit:
    """A published fit of one law: ``coefficients`` in Pa as published (Abaqus convention, see
    the module), ``source`` the publication (authors, year, journal, table)."""

    law: str
    coefficients: tuple
    source: str

    def __post_init__(self):
        if self.law not in LAWS:
            raise ValueError(f"unknown law '{self.law}' (choose from {', '.join(LAWS)})")
        if not self.source.strip():
            raise ValueError("a fit must state its source (authors, year, journal, table)")
        if self.law == "ogden":
            object.__setattr__(self, "coefficients",
                               tuple((float(m), float(a)) for m, a in self.coefficients))
        else:
            object.__setattr__(self, "coefficients", tuple(float(c) for c in self.coefficients))
        if self.mu0 <= 0.0:
            raise ValueError(f"{self.law}: the small-strain shear modulus μ0 = {self.mu0:g} Pa "
                             "must be positive")

    @property
    def mu0(self) -> float:
        """Small-strain shear modulus: ``2 (C10 + C01)``, ``2 C10`` or ``Σ μ_p``."""
        c = self.coefficients
        if self.law == "mooney_rivlin":
            return 2.0 * (c[0] + c[1])
        if self.law == "yeoh":
            return 2.0 * c[0]
        return fsum(m for m, _ in c)

    @property
    def shape(self) -> tuple:
        """The coefficients divided by ``μ0`` (the energies' ``shape``)."""
        mu0 = self.mu0
        if self.law == "ogden":
            return tuple((m / mu0, a) for m, a in self.coefficients)
        return tuple(c / mu0 for c in self.coefficients)


@dataclass(frozen=True)
class Preset:
    """A material: its fits (the first is its own law) and the ν it is used with."""

    name: str
    title: str
    fits: tuple
    nu: float = DEFAULT_NU

    def __post_init__(self):
        object.__setattr__(self, "fits", tuple(self.fits))
        if not self.fits:
            raise ValueError(f"preset '{self.name}': at least one fit")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"preset '{self.name}': nu must lie in (-1, 0.5)")

    @property
    def law(self) -> str:
        return self.fits[0].law

    def fit(self, law: str | None = None) -> Fit:
        """The fit of ``law`` (the preset's own without one); ``KeyError`` if it has none."""
        law = law or self.law
        for f in self.fits:
            if f.law == law:
                return f
        raise KeyError(law)

    def laws(self) -> tuple:
        return tuple(f.law for f in self.fits)


#: the registered presets, by name (the shipped ones, and any a case file registers)
PRESETS: dict[str, Preset] = {}


def register(preset: Preset) -> Preset:
    """Make ``preset`` selectable as ``--set material=NAME``; returns it."""
    if not preset.name or preset.name != preset.name.strip() or " " in preset.name:
        raise ValueError(f"preset name '{preset.name}': one word, no spaces")
    PRESETS[preset.name] = preset
    return preset


def unregister(name: str) -> None:
    PRESETS.pop(name, None)


def get_preset(name: str) -> Preset:
    """The preset ``name``; ``KeyError`` if none is registered under it."""
    return PRESETS[name]


def fit_for(preset: Preset, model: str) -> Fit:
    """The fit a model uses with ``preset``: the model's own law for the rubber laws, the
    preset's law otherwise (``linear``, ``gnl``, ``neohookean``, ``wang``); ``KeyError`` if the
    preset has no fit of the law asked for."""
    return preset.fit(model if model in LAWS else None)


def law_for(model: str, material: str):
    """The :class:`~pacto_ng.physics.hyperelastic.Law` a model uses: a rubber ``model``'s own
    law, or for ``wang`` the hyperelastic law it wraps (None: its default Neo-Hookean), with the
    preset's shape if ``material`` names one, else :data:`DEFAULT_SHAPES`."""
    if material:
        if model not in LAWS + ("wang",):
            return None
        fit = fit_for(get_preset(material), model)
        return Law(fit.law, fit.shape)
    if model in LAWS:
        return Law(model, DEFAULT_SHAPES[model])
    return None


# --------------------------------------------------------------------------------------------
# shipped presets: Yeoh fits in Pa (the sources give MPa with mm; converted here, nothing else)
# --------------------------------------------------------------------------------------------
_SOROTOKI = ("SOROTOKI, the soft-robotics toolkit of B. Caasenbrood (Eindhoven University of "
             "Technology), material preset +preset/+material/{}.m, Yeoh C1, C2, C3 in MPa "
             "(github.com/BJCaasenbrood/SorotokiCode, commit f3c63b6)")

#: the presets the toolkit ships (registered on import)
SHIPPED = (
    Preset("ecoflex-00-30", "Smooth-On Ecoflex 00-30 (cast silicone, Shore 00-30)", (
        Fit("yeoh", (17.0e3, -0.2e3, 0.023e3), _SOROTOKI.format("Ecoflex0030")),)),
    Preset("dragonskin-30", "Smooth-On Dragon Skin 30 (cast silicone, Shore 30A)", (
        Fit("yeoh", (0.1536e6, 0.0016e6, 0.0), _SOROTOKI.format("Dragonskin30")),)),
    Preset("elastic-50a", "Formlabs Elastic 50A (SLA-printed elastomer)", (
        Fit("yeoh", (0.5056e6, 0.0, 0.002562e6),
            "M. S. Xavier, C. D. Tawk, Y. K. Yong, A. J. Fleming (2021), Sensors and Actuators "
            "A: Physical, doi:10.1016/j.sna.2021.113199, Yeoh fit of Elastic 50A, as given in "
            + _SOROTOKI.format("Elastic50A")),)),
)
for _preset in SHIPPED:
    register(_preset)
