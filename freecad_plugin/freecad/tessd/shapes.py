"""Reading FreeCAD objects into plain inputs that a worker thread can use.

Every task reads the document here, on the GUI thread, and nothing later: a Part object becomes
a :class:`PartInput` (its shape, placed in the world or in its own frame, its label and the
colours of its view provider when the GUI is up), a Mesh object a :class:`MeshInput` (positions
and triangles as numpy arrays, its segments as face groups). The worker then exports and sends
those without touching a document object, so the GUI may go on while the daemon works.

Which objects: the arguments may be document objects, their names or labels, or a list of
them. Containers (App::Part, groups) stand for the visible Part and Mesh objects inside them,
recursively (a container's hidden children are left out, as on screen; an object named
explicitly is always taken). A Part object is anything with faces through `Part.getShape`
(Part features, PartDesign bodies, App::Links to them); a Mesh object is a Mesh::Feature or a
link to one.

Placements: FreeCAD places an object by its own Placement and those of the App::Parts (any
GeoFeatureGroup) above it; plain groups place nothing. :func:`world_placement` is that product
(what `getGlobalPlacement` gives, and App::Links have no such method in 0.20). :func:`document_tree`
keeps the chain as nodes instead, for the USD export's Xforms.
"""

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import FreeCAD
import numpy as np
import Part

RGB = Tuple[float, float, float]


@dataclass
class PartInput:
    """A Part object's shape, ready for the B-Rep export on any thread."""

    name: str
    label: str
    #: `Part.Shape` in the frame asked for (world, or the object's own frame).
    shape: Any
    #: One RGB per face of ``shape.Faces`` (the view provider's), or None without the GUI.
    colors: Optional[List[RGB]] = None
    #: What identifies this shape's tessellation (for the tessellation cache).
    key: Tuple = ()


@dataclass
class MeshInput:
    """A Mesh object's triangles, in the frame asked for."""

    name: str
    label: str
    positions: np.ndarray  # f64 [V, 3]
    triangles: np.ndarray  # int64 [F, 3]
    #: Per facet, the index of its mesh segment (facets in no segment: ``group_count``), or None
    #: when the mesh has no segments.
    groups: Optional[np.ndarray] = None
    group_count: int = 0
    #: One RGB for the whole mesh (the view provider's ShapeColor), or None without the GUI.
    colors: Optional[List[RGB]] = None


@dataclass
class Node:
    """A node of the document tree for the USD export: a container (App::Part or group) with
    children, or a leaf holding an input in its own frame."""

    name: str
    label: str
    #: The node's placement relative to its parent (a `FreeCAD.Placement`), None for identity.
    placement: Any = None
    children: List["Node"] = field(default_factory=list)
    leaf: Any = None


# -- which objects -------------------------------------------------------------------------


def is_container(obj: Any) -> bool:
    """App::Part and plain groups: they stand for their children."""
    return obj.isDerivedFrom("App::Part") or obj.isDerivedFrom("App::DocumentObjectGroup")


def _target(obj: Any) -> Any:
    """The object a link points to (the object itself when it is no link)."""
    getter = getattr(obj, "getLinkedObject", None)
    target = getter(True) if getter is not None else None
    return target if target is not None else obj


def is_mesh(obj: Any) -> bool:
    return _target(obj).isDerivedFrom("Mesh::Feature")


def is_part(obj: Any) -> bool:
    if is_container(obj) or is_mesh(obj):
        return False
    try:
        shape = Part.getShape(obj)
    except Exception:  # not a geometric object
        return False
    return not shape.isNull() and len(shape.Faces) > 0


def _lookup(doc: Any, ref: str) -> Any:
    obj = doc.getObject(ref) if doc is not None else None
    if obj is None and doc is not None:
        found = doc.getObjectsByLabel(ref)
        obj = found[0] if found else None
    if obj is None:
        where = "document %s" % doc.Name if doc is not None else "no open document"
        raise ValueError("no object named %r in %s" % (ref, where))
    return obj


def resolve(objects: Any, doc: Any = None) -> List[Any]:
    """The Part and Mesh objects that ``objects`` stands for (see the module's notes), each
    once, in order. Raises ValueError naming an object that is neither, or when none is left."""
    if objects is None:
        raise ValueError("no objects given")
    if isinstance(objects, (str, bytes)) or hasattr(objects, "isDerivedFrom"):
        objects = [objects]
    out: List[Any] = []
    seen = set()

    def visit(obj: Any, explicit: bool) -> None:
        key = (obj.Document.Name, obj.Name)
        if key in seen:
            return
        seen.add(key)
        if is_container(obj):
            for child in obj.Group:
                if getattr(child, "Visibility", True):
                    visit(child, False)
            return
        if is_mesh(obj) or is_part(obj):
            out.append(obj)
        elif explicit:
            raise ValueError("%s (%s) is neither a Part object with faces nor a Mesh object"
                             % (obj.Label, obj.TypeId))

    for ref in objects:
        visit(_lookup(doc or FreeCAD.ActiveDocument, ref) if isinstance(ref, str) else ref, True)
    if not out:
        raise ValueError("no Part or Mesh object among the objects given")
    return out


def document_of(objects: Sequence[Any], doc: Any = None) -> Any:
    """The document to add results to: ``doc``, else the objects', else the active one."""
    if doc is not None:
        return doc
    if objects:
        return objects[0].Document
    return FreeCAD.ActiveDocument


# -- placements ------------------------------------------------------------------------------


def parent(obj: Any) -> Any:
    """The container shown above ``obj`` in the tree: its group, else its App::Part."""
    p = obj.getParentGroup() if hasattr(obj, "getParentGroup") else None
    if p is None and hasattr(obj, "getParentGeoFeatureGroup"):
        p = obj.getParentGeoFeatureGroup()
    return p


def ancestors(obj: Any) -> List[Any]:
    """The containers above ``obj``, outermost first."""
    chain, seen = [], {obj.Name}
    p = parent(obj)
    while p is not None and p.Name not in seen:
        seen.add(p.Name)
        chain.append(p)
        p = parent(p)
    return chain[::-1]


def places_children(obj: Any) -> bool:
    """Whether a container's Placement moves its children (App::Part, bodies), unlike groups."""
    return obj.hasExtension("App::GeoFeatureGroupExtension") and hasattr(obj, "Placement")


def own_placement(obj: Any) -> Any:
    """What Part.getShape(obj, transform=False) leaves out: the object's own Placement."""
    return getattr(obj, "Placement", None) or FreeCAD.Placement()


def world_placement(obj: Any) -> Any:
    """The placement of ``obj`` in the document: its App::Parts' placements times its own."""
    world = FreeCAD.Placement()
    for a in ancestors(obj):
        if places_children(a):
            world = world.multiply(a.Placement)
    return world.multiply(own_placement(obj))


# -- inputs ----------------------------------------------------------------------------------


def _view_colors(obj: Any, count: int, per_face: bool) -> Optional[List[RGB]]:
    """The view provider's colours (GUI only): per face from DiffuseColor when it has one
    entry per face, else ShapeColor; None in console mode."""
    if not FreeCAD.GuiUp:
        return None
    vobj = getattr(obj, "ViewObject", None)
    if vobj is None or not hasattr(vobj, "ShapeColor"):
        vobj = getattr(_target(obj), "ViewObject", None)
    if vobj is None:
        return None
    diffuse = list(getattr(vobj, "DiffuseColor", None) or ())
    if per_face and len(diffuse) == count and count > 0:
        return [tuple(float(x) for x in c[:3]) for c in diffuse]
    color = getattr(vobj, "ShapeColor", None)
    if color is None:
        return None
    return [tuple(float(x) for x in color[:3])] * count


def part_input(obj: Any, frame: str = "world") -> PartInput:
    """A Part object's shape in the world (``frame="world"``: the shape as it is seen) or in
    its own frame (``"local"``: without its own placement or its containers')."""
    local = Part.getShape(obj, transform=False)
    placement = world_placement(obj) if frame == "world" else FreeCAD.Placement()
    box = local.BoundBox
    # hashCode() is the TShape's address (and location): reused once a shape is freed, so the
    # counts and box make a stale match after a recompute all but impossible.
    key = (obj.Document.Name, obj.Name, local.hashCode(), len(local.Faces), len(local.Edges),
           (box.XMin, box.YMin, box.ZMin, box.XMax, box.YMax, box.ZMax),
           tuple(placement.toMatrix().A))
    # A deep copy (0.17 s per 1000 faces): the worker then shares nothing with the document's
    # shape, whose edges the GUI's own meshing (BRepMesh, on the GUI thread) may extend while
    # the export reads them.
    shape = local.copy()
    shape.Placement = placement.multiply(local.Placement)
    colors = _view_colors(obj, len(shape.Faces), per_face=True)
    return PartInput(obj.Name, obj.Label, shape, colors, key)


def mesh_input(obj: Any, frame: str = "world") -> MeshInput:
    """A Mesh object's triangles in the world or in its own frame (as :func:`part_input`)."""
    target = _target(obj)
    mesh = target.Mesh.copy()
    placement = world_placement(obj) if frame == "world" else FreeCAD.Placement()
    if target is not obj and getattr(obj, "LinkTransform", False):
        placement = placement.multiply(target.Placement)
    mesh.Placement = placement
    points, facets = mesh.Topology
    positions = np.array([(p.x, p.y, p.z) for p in points], dtype=np.float64).reshape(-1, 3)
    triangles = np.array(facets, dtype=np.int64).reshape(-1, 3)
    groups, count = None, mesh.countSegments()
    if count:
        groups = np.full(len(triangles), count, dtype=np.int64)
        for s in range(count):
            groups[np.asarray(mesh.getSegment(s), dtype=np.int64)] = s
    return MeshInput(obj.Name, obj.Label, positions, triangles, groups, count,
                     _view_colors(obj, 1, per_face=False))


def inputs(objects: Sequence[Any], frame: str = "world") -> List[Any]:
    """The input of each resolved object (:func:`resolve`), in order."""
    return [mesh_input(o, frame) if is_mesh(o) else part_input(o, frame) for o in objects]


def document_tree(objects: Sequence[Any]) -> List[Node]:
    """The resolved objects with the containers above them, as top-level nodes in document
    order: leaves in their own frame with their own placement, containers with theirs (None
    for groups). The product along a path is each leaf's :func:`world_placement`."""
    roots: List[Node] = []
    nodes: Dict[str, Node] = {}

    def attach(node: Node, parent_node: Optional[Node]) -> None:
        (parent_node.children if parent_node is not None else roots).append(node)

    for obj in objects:
        above: Optional[Node] = None
        for a in ancestors(obj):
            node = nodes.get(a.Name)
            if node is None:
                node = Node(a.Name, a.Label, a.Placement if places_children(a) else None)
                nodes[a.Name] = node
                attach(node, above)
            above = node
        leaf = mesh_input(obj, "local") if is_mesh(obj) else part_input(obj, "local")
        attach(Node(obj.Name, obj.Label, own_placement(obj), leaf=leaf), above)
    return roots


__all__ = ["MeshInput", "Node", "PartInput", "ancestors", "document_of", "document_tree",
           "inputs", "is_container", "is_mesh", "is_part", "mesh_input", "part_input",
           "resolve", "world_placement"]
