"""The console API of the tessd workbench: what every command does, callable from a macro.

    from freecad.tessd import api
    meshes = api.tessellate(doc.Box, tolerance="0.05mm")            # [Box_mesh]
    api.simplify(doc.Box_mesh, method="quality", max_error="0.5%", show_partition=True)
    api.generate_lods([doc.Bracket], levels="50%,20%,5%", usd_path="/tmp/bracket.usda")
    api.export_usd(doc.Objects, "/tmp/assembly.usda")
    api.render(doc.Box, "/tmp/box.png", size=(960, 540), view="iso")

``objects`` is a document object, its name or label, or a list of them; App::Parts and groups
stand for the visible Part and Mesh objects inside them. Lengths are given as the CLI takes
them: numbers (millimetres), strings with a unit ("0.1mm"), or percentages ("0.5%") where the
operation defines one. Daemon errors raise :class:`TessdError` with the daemon's message
(``e.message``); bad arguments raise ValueError. The daemon is started when none runs
(daemon_link.py: its preferences).

Each function is ``prepare_<op>(...)`` (reads the document; GUI thread), then ``Task.run()``
(the daemon's work; any thread, cancellable), then ``Task.apply()`` (adds the results in one
undo step; GUI thread). The GUI runs the same three phases with run() on a worker thread
(task.py). Keyword-only extras of the prepare functions (``doc``, and options the dialogs
show) are accepted by the functions too.
"""

from typing import Any, Dict, List, Optional

from . import camera as _camera
from . import params as _params
from . import shapes
from .task import Cancelled, Task, TessdError
from .task_lods import LodsTask
from .task_render import RenderTask
from .task_simplify import SimplifyPreviewTask, SimplifyTask, simplify_params
from .task_tessellate import TessellateTask
from .task_usd import ExportUsdTask


def _run(task: Task) -> Any:
    task.run()
    return task.apply()


def _resolve(objects: Any, doc: Any) -> tuple:
    resolved = shapes.resolve(objects, doc)
    return resolved, shapes.document_of(resolved, doc)


# -- tessellate ------------------------------------------------------------------------------


def prepare_tessellate(objects: Any, tolerance: Any = "0.1mm", angle: float = 0.5, *,
                       doc: Any = None) -> TessellateTask:
    """The :func:`tessellate` task (reads the Part objects' shapes, placed in the world)."""
    resolved, doc = _resolve(objects, doc)
    meshes = [o.Label for o in resolved if shapes.is_mesh(o)]
    if meshes:
        raise ValueError("tessellate takes Part objects; %s %s a mesh already"
                         % (", ".join(meshes), "is" if len(meshes) == 1 else "are"))
    _params.length(tolerance, "tolerance", percent=True)
    if not isinstance(angle, (int, float)) or isinstance(angle, bool):
        raise ValueError("`angle` must be a number of radians, got %r" % (angle,))
    return TessellateTask(shapes.inputs(resolved), tolerance, float(angle), doc)


def tessellate(objects: Any, tolerance: Any = "0.1mm", angle: float = 0.5, *,
               doc: Any = None) -> List[Any]:
    """One new Mesh::Feature per Part object, `<Label>_mesh`, tessellated precisely: every
    point within ``tolerance`` of the surface (a length, "0.1mm", or a percentage of the part's
    bounding-box diagonal, "0.05%"), facets turning by at most ``angle`` radians, watertight for
    a closed part (edges discretised once, vertices shared), one mesh segment per B-Rep face
    (segment i is `shape.Faces[i]`). The meshes are placed in the world as the parts are seen.
    Returns the new objects."""
    return _run(prepare_tessellate(objects, tolerance, angle, doc=doc))


# -- simplify --------------------------------------------------------------------------------


def prepare_simplify(objects: Any, method: str = "complexity", cells: Any = None,
                     cell_size: Any = None, max_error: Any = None, target: Any = None,
                     representative: str = "quadric", show_partition: bool = False, *,
                     preserve_boundaries: bool = False, weighting: Optional[str] = None,
                     doc: Any = None) -> SimplifyTask:
    """The :func:`simplify` task (reads the objects; Part objects are tessellated in run())."""
    resolved, doc = _resolve(objects, doc)
    p = simplify_params(method, cells, cell_size, max_error, target, representative,
                        show_partition, preserve_boundaries, weighting)
    return SimplifyTask(shapes.inputs(resolved), p, doc)


def simplify(objects: Any, method: str = "complexity", cells: Any = None, cell_size: Any = None,
             max_error: Any = None, target: Any = None, representative: str = "quadric",
             show_partition: bool = False, *, preserve_boundaries: bool = False,
             weighting: Optional[str] = None, doc: Any = None) -> List[Any]:
    """Simplified copies of Mesh and Part objects by vertex clustering (paper 004), as `tessd
    simplify` does: ``method`` "grid" (``cells`` per axis of the bounding box, or cubic cells of
    ``cell_size``), "quality" (the surface moves at most ``max_error``: a length, or "0.5%" of
    the largest side) or "complexity" (``target`` vertices: a count or "20%"); cells merge their
    vertices to the ``representative`` ("quadric", "barycenter", "heaviest"). Part objects are
    tessellated first (0.1 mm). Returns the new `<Label>_simplified` Mesh::Features (segments
    kept); ``show_partition`` also adds `<Label>_partition`, the cells as wire boxes."""
    return _run(prepare_simplify(objects, method, cells, cell_size, max_error, target,
                                 representative, show_partition,
                                 preserve_boundaries=preserve_boundaries, weighting=weighting,
                                 doc=doc))


def prepare_simplify_preview(obj: Any, method: str = "complexity", cells: Any = None,
                             cell_size: Any = None, max_error: Any = None, target: Any = None,
                             representative: str = "quadric", *,
                             preserve_boundaries: bool = False, weighting: Optional[str] = None,
                             doc: Any = None) -> SimplifyPreviewTask:
    """The Simplify dialog's live preview of one object: run() simplifies without output and
    apply() returns ``{"vertices", "faces", "surface_error", "report"}``, touching nothing.
    A Part's tessellation is kept between previews (tessellation.py)."""
    resolved, doc = _resolve(obj, doc)
    if len(resolved) != 1:
        raise ValueError("the preview simplifies one object; %d given" % len(resolved))
    p = simplify_params(method, cells, cell_size, max_error, target, representative, False,
                        preserve_boundaries, weighting)
    return SimplifyPreviewTask(shapes.inputs(resolved), p, doc)


# -- LODs ------------------------------------------------------------------------------------


def prepare_generate_lods(objects: Any, levels: Any = "50%,20%,5%", usd_path: Optional[str] = None,
                          *, method: str = "complexity", representative: Optional[str] = None,
                          lod_schema: str = "variants", doc: Any = None) -> LodsTask:
    """The :func:`generate_lods` task."""
    resolved, doc = _resolve(objects, doc)
    lod: Dict[str, Any] = {"method": method, "lod_schema": lod_schema}
    if representative is not None:
        lod["representative"] = representative
    return LodsTask(shapes.inputs(resolved), _params.levels(levels), usd_path, lod, doc)


def generate_lods(objects: Any, levels: Any = "50%,20%,5%", usd_path: Optional[str] = None, *,
                  method: str = "complexity", representative: Optional[str] = None,
                  lod_schema: str = "variants", doc: Any = None) -> List[Any]:
    """A chain of levels of detail per object: the group `<Label>_LODs` holding `<Label>_LOD0`
    (the object's mesh; a Part's 0.1 mm tessellation) to `<Label>_LOD<n>`, one level per goal
    of ``levels`` ("50%,20%,5%": vertex percentages, as `tessd lod --levels`). With
    ``usd_path`` the chain is also written as a USD stage (a `LOD` variant set; several objects:
    `<stem>_<Label>.usda` each). Returns the groups, one per object."""
    return _run(prepare_generate_lods(objects, levels, usd_path, method=method,
                                      representative=representative, lod_schema=lod_schema,
                                      doc=doc))


# -- USD -------------------------------------------------------------------------------------


def prepare_export_usd(objects: Any, path: str, tolerance: Any = "0.1mm", *,
                       doc: Any = None) -> ExportUsdTask:
    """The :func:`export_usd` task (reads the objects in their own frames, the containers
    above them and the view providers' colours)."""
    resolved, doc = _resolve(objects, doc)
    _params.length(tolerance, "tolerance", percent=True)
    return ExportUsdTask(shapes.document_tree(resolved), path, tolerance,
                         doc.Name if doc is not None else "FreeCAD", doc)


def export_usd(objects: Any, path: str, tolerance: Any = "0.1mm", *, doc: Any = None) -> str:
    """One USD stage (`.usda`) of the objects: the document's tree as Xforms (App::Parts with
    their placements, groups), each Part object a mesh tessellated to ``tolerance`` with its
    own placement and a GeomSubset per B-Rep face, each Mesh object a mesh with a GeomSubset
    per segment; display colours from the view providers when the GUI is up; millimetres,
    Z up. Returns the stage's path."""
    return _run(prepare_export_usd(objects, path, tolerance, doc=doc))


# -- render ----------------------------------------------------------------------------------


def prepare_render(objects: Any, path: str, size: Any = (1280, 720), view: str = "iso",
                   cracks: str = "object", *, shading: Optional[str] = None,
                   doc: Any = None) -> RenderTask:
    """The :func:`render` task (reads the shapes and, for ``view="active"``, the active 3D
    view's camera: GUI thread)."""
    resolved, doc = _resolve(objects, doc)
    width, height = _params.image_size(size)
    cam = None
    if view == "active":
        cam = _camera.active_view_camera(width / height if height else 1.0)
    else:
        _camera.check_view(view)
    extra = {"shading": shading} if shading else None
    return RenderTask(shapes.inputs(resolved), path, (width, height), view, cam, cracks, extra,
                      doc)


def render(objects: Any, path: str, size: Any = (1280, 720), view: str = "iso",
           cracks: str = "object", *, shading: Optional[str] = None, doc: Any = None) -> str:
    """A PNG of the objects, rendered precisely by the daemon: Part objects from their B-Rep
    (per-frame tessellation, GPU trimming, ``cracks`` between faces filled by "object" ray
    casting, "image" filling or "none"), Mesh objects as meshes. ``size`` is (width, height)
    or "WxH"; ``view`` a standard view fitted to the objects ("iso", "front", "back", "left",
    "right", "top", "bottom") or "active", the active 3D view's camera (GUI only). Returns the
    PNG's path."""
    return _run(prepare_render(objects, path, size, view, cracks, shading=shading, doc=doc))


__all__ = ["Cancelled", "Task", "TessdError", "export_usd", "generate_lods",
           "prepare_export_usd", "prepare_generate_lods", "prepare_render",
           "prepare_simplify", "prepare_simplify_preview", "prepare_tessellate", "render",
           "simplify", "tessellate"]
