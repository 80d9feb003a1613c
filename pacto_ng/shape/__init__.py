"""Body-fitted shape refinement of a part: the mesh moved by a deformation
(:mod:`~pacto_ng.shape.deformation`) and the shape gradient of the part's output by the
adjoint (:mod:`~pacto_ng.shape.gradient`), as blocks of a :class:`~pacto_ng.core.Chain`."""
from .deformation import ShapeSpace, volume, volume_integrals
from .gradient import PartResponse, ShapeResponse, ShapeVolume

__all__ = ["PartResponse", "ShapeResponse", "ShapeSpace", "ShapeVolume", "volume",
           "volume_integrals"]
