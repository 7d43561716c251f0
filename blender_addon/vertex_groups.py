"""Vertex group weights of a mesh as one [groups, vertices] array.

Blender's Python API has no bulk access to vertex group weights: the only way is to walk
`mesh.vertices[i].groups`, about 1.5 µs a vertex (1 s for a 655 362-vertex mesh). Geometry
nodes, though, see each vertex group as a point attribute. So for a large mesh that is an
object's own data, a temporary node tree stores every group as a float attribute
(`.tessd_vg<i>`), a temporary object using the mesh, in a temporary scene of its own (the
user's scenes and view layers are never touched), is evaluated with that tree as its only
modifier, and the attributes are read with `foreach_get` (12 ms for the same mesh, identical
weights). The scene, the object and the tree are removed again before returning, whatever
happens.

Where that path cannot work (an evaluated mesh from `to_mesh`, which no object can use; a
group name that is also an attribute's, which the node would read instead) or fails in any
way, the loop gives the same answer.
"""

import bpy
import numpy as np

#: Below this many vertices the loop is quicker than evaluating a node tree.
BULK_MIN_VERTICES = 20000
#: Names of the temporary node tree, scene and object.
TEMP_NAME = ".tessd_vertex_groups"
#: The attribute holding group i on the evaluated mesh is ATTRIBUTE + str(i).
ATTRIBUTE = ".tessd_vg"


def weights(mesh, obj, names):
    """f32 [len(names), vertices]: the weight of each vertex in the group names[i] (0 where
    the vertex is not in it). `mesh` is `obj`'s own data or the evaluated mesh of `obj`."""
    if len(mesh.vertices) >= BULK_MIN_VERTICES and bulk_possible(mesh, obj, names):
        try:
            out = weights_bulk(mesh, names)
        except (RuntimeError, TypeError, ValueError, KeyError, AttributeError):
            out = None  # e.g. a node of another Blender version: the loop gives the same answer
        if out is not None and agrees(mesh, names, out):
            return out
    return weights_loop(mesh, names)


def agrees(mesh, names, out, samples=1024):
    """Whether `out` holds the loop's weights at `samples` evenly spaced vertices (a check
    of the node path, which another Blender version could wire differently)."""
    n = len(mesh.vertices)
    picks = np.unique(np.linspace(0, n - 1, min(samples, n)).astype(np.int64))
    want = np.zeros((len(names), len(picks)), dtype=np.float32)
    vertices = mesh.vertices
    for j, i in enumerate(picks.tolist()):
        for g in vertices[i].groups:
            if g.group < len(names):
                want[g.group, j] = g.weight
    return bool(np.array_equal(want, out[:, picks]))


def bulk_possible(mesh, obj, names):
    """Whether :func:`weights_bulk` can read `mesh`: the object's own mesh (a datablock an
    object can use) and no group named as an attribute (Blender refuses an attribute named as
    a group, but not a group named as an attribute)."""
    return obj.data == mesh and not any(mesh.attributes.get(name) is not None for name in names)


def weights_loop(mesh, names):
    """The weights by walking every vertex's groups (any mesh; slow for large ones)."""
    out = np.zeros((len(names), len(mesh.vertices)), dtype=np.float32)
    count = len(names)
    for v in mesh.vertices:
        for g in v.groups:
            if g.group < count:
                out[g.group, v.index] = g.weight
    return out


def weights_bulk(mesh, names):
    """The weights through geometry nodes (see the module's doc); `mesh` must be a mesh
    datablock whose vertex groups include `names`."""
    tree = bpy.data.node_groups.new(TEMP_NAME, 'GeometryNodeTree')
    scene = bpy.data.scenes.new(TEMP_NAME)
    holder = None
    try:
        _store_groups(tree, names)
        holder = bpy.data.objects.new(TEMP_NAME, mesh)
        scene.collection.objects.link(holder)
        holder.modifiers.new("tessd", 'NODES').node_group = tree
        with bpy.context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
            depsgraph = bpy.context.evaluated_depsgraph_get()
        evaluated = holder.evaluated_get(depsgraph)
        result = evaluated.to_mesh()
        try:
            if len(result.vertices) != len(mesh.vertices):
                raise ValueError("the node tree changed the vertex count")
            out = np.empty((len(names), len(mesh.vertices)), dtype=np.float32)
            for i in range(len(names)):
                result.attributes[ATTRIBUTE + str(i)].data.foreach_get("value", out[i])
            return out
        finally:
            evaluated.to_mesh_clear()
    finally:
        if holder is not None:
            bpy.data.objects.remove(holder)
        bpy.data.scenes.remove(scene)
        bpy.data.node_groups.remove(tree)


def _store_groups(tree, names):
    """Group Input → one Store Named Attribute per group (`.tessd_vg<i>` = the group's
    weight, read by a Named Attribute node) → Group Output."""
    def socket(sockets, name):
        # The available one: older versions keep a hidden socket per data type.
        found = [s for s in sockets if s.name == name]
        return next((s for s in found if getattr(s, "enabled", True)), found[0])

    tree.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    tree.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    nodes, links = tree.nodes, tree.links
    geometry = nodes.new("NodeGroupInput").outputs[0]
    for i, name in enumerate(names):
        read = nodes.new("GeometryNodeInputNamedAttribute")
        read.data_type = 'FLOAT'
        socket(read.inputs, "Name").default_value = name
        store = nodes.new("GeometryNodeStoreNamedAttribute")
        store.data_type = 'FLOAT'
        store.domain = 'POINT'
        socket(store.inputs, "Name").default_value = ATTRIBUTE + str(i)
        links.new(geometry, socket(store.inputs, "Geometry"))
        links.new(socket(read.outputs, "Attribute"), socket(store.inputs, "Value"))
        geometry = socket(store.outputs, "Geometry")
    links.new(geometry, nodes.new("NodeGroupOutput").inputs[0])
