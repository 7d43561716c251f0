"""Everything a mesh carries besides positions, faces and materials, to and from the
protocol's attribute arrays (docs/protocol.md, "Mesh arrays"): `point:<name>`,
`corner:<name>`, `face:<name>` (f32, one row per vertex / corner / face) and `sharp_edges`.

- Generic attributes of the point, corner and face domains of every numeric type (UV maps
  and colour attributes are such attributes) go as they are, converted to f32; the daemon
  averages point and corner values per cell and gives a face its source face's value, and
  they come back as the same Blender type (integers rounded, booleans above 0.5).
- Vertex groups go as one point attribute `vertex_group:<name>` each (weight 0 where the
  vertex is not in the group); the averaged weights come back normalised per vertex when
  the input's were (every weighted vertex summing to 1, as skinning wants).
- Shape keys go as point attributes `shape_key:<name>` holding each key's offset from the
  reference key, so they go through the same clustering as the positions; a result's key
  is its positions plus the averaged offsets.
- Sharp edges (`sharp_edge`) go as vertex pairs and come back on the result's edges.

What cannot travel (edge attributes other than sharp edges and creases, strings, shape keys
of an object whose modifiers are applied) is named by :func:`describe_dropped`, so the
operator's report lists it instead of losing it silently.
"""

import numpy as np

from . import vertex_groups

#: Prefixes of the point attributes that stand for vertex groups and shape keys.
VERTEX_GROUP = "vertex_group:"
SHAPE_KEY = "shape_key:"

#: Blender data type -> (components, the `foreach_get` key, the numpy dtype Blender copies
#: without converting element by element: see convert.read).
TYPES = {
    'FLOAT': (1, "value", np.float32), 'INT': (1, "value", np.int32),
    'INT8': (1, "value", np.int8), 'BOOLEAN': (1, "value", np.bool_),
    'FLOAT2': (2, "vector", np.float32), 'INT32_2D': (2, "value", np.int32),
    'INT16_2D': (2, "value", np.int16), 'FLOAT_VECTOR': (3, "vector", np.float32),
    'FLOAT_COLOR': (4, "color", np.float32), 'BYTE_COLOR': (4, "color", np.float32),
    'QUATERNION': (4, "value", np.float32), 'FLOAT4X4': (16, "value", np.float32),
}
INTEGER_TYPES = {'INT', 'INT8', 'INT32_2D', 'INT16_2D'}
DOMAINS = {'POINT': "point", 'CORNER': "corner", 'FACE': "face"}
#: Attributes the conversion handles itself (positions, materials, creases, sharp edges,
#: custom normals: see convert.py and shading.py).
HANDLED = {"position", "material_index", "sharp_edge", "crease_edge", "custom_normal"}


class Sent:
    """What one mesh sent besides its geometry, kept for rebuilding the results.

    `generic`: (name, domain, data_type) of the generic attributes; `groups`: vertex group
    names in index order and whether their weights were normalised; `keys`: the shape keys'
    settings; `dropped`: names of what could not be sent."""

    def __init__(self):
        self.generic = []
        self.groups = []
        self.groups_normalized = False
        self.keys = []
        self.active_uv = None
        self.active_render_uv = None
        self.active_color = None
        self.default_color = None
        self.dropped = []
        self.uv_name = None
        self.all_sharp_faces = False
        self.missing = set()


def _read(attr, n):
    comps, key, dtype = TYPES[attr.data_type]
    buf = np.empty(n * comps, dtype=dtype)
    attr.data.foreach_get(key, buf)
    values = buf.astype(np.float32, copy=False)
    return values.reshape(n, comps) if comps > 1 else values


def collect(mesh, obj, arrays, sent, skip=(), uniform_sharp_face=True):
    """Adds the generic attributes, vertex groups, shape keys and sharp edges of `mesh`
    to `arrays` and records them in `sent` (a :class:`Sent`). `skip` names attributes
    already sent another way (the UV map sent as `uvs`). Corner values are in face order
    as Blender stores them (convert.corner_vertices). With `uniform_sharp_face` false (the
    result only comes back to Blender: no file keeps the attribute), a `sharp_face` that is
    the same on every face is not sent: all false, a result without it is smooth everywhere;
    all true (`sent.all_sharp_faces`), every result face is made flat."""
    sizes = {"POINT": len(mesh.vertices), "CORNER": len(mesh.loops), "FACE": len(mesh.polygons)}
    for attr in mesh.attributes:
        name = attr.name
        if name.startswith(".") or name in HANDLED or name in skip:
            continue
        if attr.domain not in DOMAINS or attr.data_type not in TYPES:
            sent.dropped.append("%s (%s %s attribute)" % (name, attr.domain.lower(),
                                                          attr.data_type.lower()))
            continue
        values = _read(attr, sizes[attr.domain])
        if (name == "sharp_face" and attr.domain == 'FACE' and not uniform_sharp_face
                and (values.all() or not values.any())):
            # The same on every face: every result face (each has a source face) gets it too,
            # so it need not travel (a flat-shaded mesh saves 4 bytes a face each way).
            sent.all_sharp_faces = bool(values.all()) and len(values) > 0
            continue
        arrays["%s:%s" % (DOMAINS[attr.domain], name)] = values
        sent.generic.append((name, attr.domain, attr.data_type))
    uv = mesh.uv_layers
    sent.active_uv = uv.active.name if uv.active is not None else None
    sent.active_render_uv = next((u.name for u in uv if u.active_render), None)
    colors = mesh.color_attributes
    sent.active_color = colors.active_color_name or None
    sent.default_color = colors.default_color_name or None
    sharp = mesh.attributes.get("sharp_edge")
    if sharp is not None and sharp.domain == 'EDGE' and len(mesh.edges):
        flags = np.empty(len(mesh.edges), dtype=bool)
        sharp.data.foreach_get("value", flags)
        if flags.any():
            arrays["sharp_edges"] = edge_vertices(mesh)[flags]
    if obj is not None:
        _collect_groups(mesh, obj, arrays, sent)
    return sent


def edge_vertices(mesh):
    """The two vertices of every edge, [E, 2] u32."""
    verts = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    attr = mesh.attributes.get(".edge_verts")
    if attr is not None:
        attr.data.foreach_get("value", verts)
    else:
        mesh.edges.foreach_get("vertices", verts)
    return verts.view(np.uint32).reshape(-1, 2)


def _collect_groups(mesh, obj, arrays, sent):
    names = [g.name for g in obj.vertex_groups]
    if names and len(mesh.vertices):
        weights = vertex_groups.weights(mesh, obj, names)
        for i, name in enumerate(names):
            arrays["point:" + VERTEX_GROUP + name] = weights[i]
        sums = weights.sum(axis=0)
        weighted = sums > 0
        sent.groups = names
        sent.groups_normalized = bool(weighted.any() and np.allclose(sums[weighted], 1.0, atol=1e-3))


def _key_positions(block, n):
    """A shape key's positions, f32 [n * 3]: its `points` (Blender 4.1+) copy in one go, its
    `data` element by element."""
    co = np.empty(n * 3, dtype=np.float32)
    (block.points if hasattr(block, "points") else block.data).foreach_get("co", co)
    return co


def collect_shape_keys(mesh, arrays, sent):
    """Each shape key but the reference as `shape_key:<name>`: its offset from the reference
    key (the positions sent)."""
    keys = mesh.shape_keys
    if keys is None or len(keys.key_blocks) < 2:
        return
    n = len(mesh.vertices)
    ref = keys.reference_key
    base = _key_positions(ref, n)
    for block in keys.key_blocks:
        if block == ref:
            continue
        arrays["point:" + SHAPE_KEY + block.name] = (_key_positions(block, n) - base).reshape(-1, 3)
    sent.keys = [dict(name=b.name, value=b.value, mute=b.mute, slider_min=b.slider_min,
                      slider_max=b.slider_max, vertex_group=b.vertex_group,
                      relative_key=b.relative_key.name, interpolation=b.interpolation,
                      reference=(b == ref))
                 for b in keys.key_blocks]


def _values(arrays, wire, prefix):
    v = arrays.get(prefix + wire)
    return None if v is None else np.asarray(v, dtype=np.float32)


def apply_generic(mesh, arrays, prefix, sent):
    """Sets the generic attributes of a new result mesh from the reply's arrays; returns the
    names the reply did not carry."""
    missing = []
    sizes = {"POINT": len(mesh.vertices), "CORNER": len(mesh.loops), "FACE": len(mesh.polygons)}
    for name, domain, data_type in sent.generic:
        values = _values(arrays, "%s:%s" % (DOMAINS[domain], name), prefix)
        comps, key, dtype = TYPES[data_type]
        if values is None or values.size != sizes[domain] * comps:
            missing.append(name)
            continue
        # Written in the attribute's own dtype, so Blender copies it in one go.
        if data_type == 'BOOLEAN':
            values = values > 0.5
        elif data_type in INTEGER_TYPES:
            info = np.iinfo(dtype)
            values = np.clip(np.rint(values), info.min, info.max).astype(dtype)
        elif data_type == 'BYTE_COLOR':
            values = np.clip(values, 0.0, 1.0)
        if data_type == 'FLOAT2' and domain == 'CORNER':
            attr = mesh.uv_layers.new(name=name, do_init=False)
            attr = mesh.attributes[attr.name]
        else:
            attr = mesh.attributes.get(name) or mesh.attributes.new(name, data_type, domain)
        attr.data.foreach_set(key, np.ascontiguousarray(values).reshape(-1))
    for uv_name, flag in ((sent.active_uv, "active"), (sent.active_render_uv, "active_render")):
        layer = mesh.uv_layers.get(uv_name) if uv_name else None
        if layer is not None:
            setattr(layer, flag, True)
    colors = mesh.color_attributes
    if sent.active_color and colors.get(sent.active_color) is not None:
        colors.active_color_name = sent.active_color
    if sent.default_color and colors.get(sent.default_color) is not None:
        colors.default_color_name = sent.default_color
    return missing


def set_edge_flags(mesh, pairs, name="sharp_edge"):
    """The boolean edge attribute `name`, true on the edges given as vertex pairs."""
    values = edge_values(mesh, pairs, np.ones(len(pairs), dtype=np.float32))
    attr = mesh.attributes.get(name) or mesh.attributes.new(name, 'BOOLEAN', 'EDGE')
    attr.data.foreach_set("value", values > 0)


def edge_values(mesh, pairs, values):
    """Per edge of `mesh`, the value given for its vertex pair (0 for edges not given)."""
    verts = edge_vertices(mesh).astype(np.int64)
    n_v = max(len(mesh.vertices), 1)
    keys = verts.min(axis=1) * n_v + verts.max(axis=1)
    order = np.argsort(keys)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    want = pairs.min(axis=1) * n_v + pairs.max(axis=1)
    out = np.zeros(len(verts), dtype=np.float32)
    if not len(verts) or not len(want):
        return out
    pos = np.clip(np.searchsorted(keys[order], want), 0, len(verts) - 1)
    found = keys[order][pos] == want
    out[order[pos[found]]] = np.asarray(values, dtype=np.float32)[found]
    return out


def apply_object_data(obj, arrays, prefix, sent):
    """Vertex groups and shape keys of a result (they need an object: `obj` uses the result
    mesh; the data stays on the mesh); returns the names the reply did not carry."""
    missing = []
    mesh = obj.data
    n = len(mesh.vertices)
    if sent.groups:
        weights = []
        for name in sent.groups:
            w = _values(arrays, "point:" + VERTEX_GROUP + name, prefix)
            if w is None or w.size != n:
                missing.append("vertex group " + name)
                w = np.zeros(n, dtype=np.float32)
            weights.append(w.reshape(-1))
        weights = np.array(weights, dtype=np.float32).reshape(len(sent.groups), n)
        if sent.groups_normalized:
            sums = weights.sum(axis=0)
            weights = np.where(sums > 0, weights / np.where(sums > 0, sums, 1.0), 0.0)
        for name, w in zip(sent.groups, weights):
            group = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
            nz = np.flatnonzero(w > 0)
            # One `add` per distinct weight (weights of a cell often repeat).
            uniq, inverse = np.unique(w[nz], return_inverse=True)
            for k, value in enumerate(uniq):
                group.add(nz[inverse == k].tolist(), float(value), 'REPLACE')
    if sent.keys:
        pos = np.empty(n * 3, dtype=np.float32)
        mesh.attributes["position"].data.foreach_get("vector", pos)
        blocks = {}
        for key in sent.keys:
            block = obj.shape_key_add(name=key["name"], from_mix=False)
            blocks[key["name"]] = block
            if key["reference"]:
                continue
            off = _values(arrays, "point:" + SHAPE_KEY + key["name"], prefix)
            if off is None or off.size != n * 3:
                missing.append("shape key " + key["name"])
                continue
            (block.points if hasattr(block, "points") else block.data).foreach_set(
                "co", pos + off.reshape(-1))
        for key in sent.keys:
            block = blocks[key["name"]]
            for prop in ("value", "mute", "slider_min", "slider_max", "vertex_group",
                         "interpolation"):
                try:
                    setattr(block, prop, key[prop])
                except (TypeError, ValueError, AttributeError):
                    pass
            if key["relative_key"] in blocks:
                block.relative_key = blocks[key["relative_key"]]
    return missing


def wire_names(sent):
    """The protocol names of the point attributes standing for groups and keys, and the
    generic attributes, as sent (to read the daemon's `dropped_attributes`)."""
    out = {}
    for name, domain, _ in sent.generic:
        out["%s:%s" % (DOMAINS[domain], name)] = name
    for name in sent.groups:
        out["point:" + VERTEX_GROUP + name] = "vertex group " + name
    for key in sent.keys:
        out["point:" + SHAPE_KEY + key["name"]] = "shape key " + key["name"]
    return out


def describe_dropped(sent, reply_dropped=()):
    """Everything of one mesh that its result lacks: what could not be sent, and what the
    daemon reported it could not carry (`dropped_attributes`)."""
    names = wire_names(sent)
    out = list(sent.dropped) + list(sent.missing)
    for wire in reply_dropped or ():
        out.append(names.get(wire, wire))
    return sorted(set(out))
