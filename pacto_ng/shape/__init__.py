"""Body-fitted shape refinement of a part: the mesh moved by a deformation
(:mod:`~pacto_ng.shape.deformation`), the shape gradient of the part's output by the adjoint
(:mod:`~pacto_ng.shape.gradient`), as blocks of a :class:`~pacto_ng.core.Chain`
(:mod:`~pacto_ng.shape.blocks`), the descent
field and step control (:mod:`~pacto_ng.shape.riesz`) and the descent loop with the volume
bounded (:mod:`~pacto_ng.shape.refine`), the moved part remeshed
(:mod:`~pacto_ng.shape.remesh`; the command ``pacto refine RUN``:
:mod:`pacto_ng.post.refine_run`)."""
from .deformation import ShapeSpace, volume, volume_integrals
from .blocks import ShapeResponse, ShapeVolume
from .gradient import PartResponse
from .refine import RefineResult, refine
from .remesh import crossing_walls, moved_field, remesh_moved
from .riesz import Quality, RieszMap, step_length

__all__ = ["PartResponse", "Quality", "RefineResult", "RieszMap", "ShapeResponse",
           "crossing_walls", "moved_field",
           "ShapeSpace", "ShapeVolume", "refine", "remesh_moved", "step_length", "volume",
           "volume_integrals"]
