"""The shape of a part as blocks of a :class:`~pacto_ng.core.Chain`: the deformation's
coefficients to the part's objective (:class:`ShapeResponse`, through
:class:`~pacto_ng.shape.gradient.PartResponse`) and to its volume (:class:`ShapeVolume`),
each with ``forward`` and ``backward``."""
from __future__ import annotations

import numpy as np

from .deformation import ShapeSpace, volume, volume_integrals
from .gradient import PartResponse, checked_objective

class ShapeResponse:
    """Block ``shape -> J``: the coefficients of the mesh deformation ``d`` on ``space`` to
    the part's objective ``J``, ``Δ`` (``objective="delta"``) or ``Δ/SE`` (``"ratio"``)
    (:class:`PartResponse`); the output is named after the objective unless ``output`` is
    given.

    forward: ``SetDeformation(d)`` (:meth:`ShapeSpace.set`), equilibrium, ``J``.
    backward: ``ḡ dJ/dV`` on ``space`` (held dofs zero; the module's Lagrangian).
    """

    def __init__(self, response: PartResponse, space: ShapeSpace, *, inputs=("shape",),
                 output: str | None = None, objective: str = "delta"):
        if space.mesh is not response.mesh:
            raise ValueError("the shape space and the response must be on the same mesh")
        self.response, self.space, self.objective = response, space, checked_objective(objective)
        self.inputs, self.output = tuple(inputs), output or objective

    def forward(self, shape) -> float:
        self.space.set(shape)
        self.response.solve()
        return self.response.value(self.objective)

    def backward(self, grad_output) -> tuple[np.ndarray]:
        return (float(grad_output) * self.response.gradient(self.space, self.objective),)


class ShapeVolume:
    """Block ``shape -> t |Ω|``, the part's volume
    (:func:`~pacto_ng.shape.deformation.volume`; ``t`` the thickness of a 2D part, 1 in 3D).

    forward: ``SetDeformation(d)``, ``t ∫_Ω dx``.
    backward: ``ḡ t ∫_Ω div V dx`` on ``space`` (``DiffShape``; held dofs zero).
    """

    def __init__(self, space: ShapeSpace, *, thickness: float = 1.0, inputs=("shape",),
                 output: str = "volume"):
        self.space, self.thickness = space, float(thickness)
        self.inputs, self.output = tuple(inputs), output

    def forward(self, shape) -> float:
        self.space.set(shape)
        return volume(self.space.mesh, self.thickness)

    def backward(self, grad_output) -> tuple[np.ndarray]:
        return (float(grad_output) * self.space.derivative(volume_integrals(self.thickness)),)
