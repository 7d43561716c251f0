"""The independent reference for tessd's render tests (issue 21): an OCP `BRepMesh` tessellation
of the part at 1e-3 of its bounding-box diagonal, ray cast by a peer ray tracer (Embree, through
`embreex` and trimesh's `RayMeshIntersector`) with the renderer's documented camera convention,
and the comparisons of tessd's face-id PNG with it.

Nothing here calls tessd to make a reference: the document tessd renders is made by the
project's exporter (`tessd.brep.ocp`), and the faces meshed here are numbered exactly as the
exporter numbers them (`TopExp::MapShapes(prepared shape, FACE)` on the shape `prepare` returns,
sewn or not), so reference face i is document face i.

Camera (docs/protocol.md, "render"): the ray of pixel (x, y) of a W x H image (row 0 at the top)
leaves the eye along `forward + sx·right + sy·up'`, `sx = (2(x+0.5)/W − 1)·tan(fov/2)·W/H`,
`sy = (1 − 2(y+0.5)/H)·tan(fov/2)`, `forward = normalize(target − eye)`,
`right = normalize(forward × up)`, `up' = right × forward`.

Images: face ids are H x W int arrays, the 0-based document face index, −1 the background (tessd's
PNG holds index + 1, 0 the background: `read_face_ids` converts). Depth is camera z (the distance
along `forward`), inf on the background.

Masks: `border` = pixels whose 3 x 3 neighbourhood in the reference holds more than one id (the
background included): silhouettes and face borders; `silhouette` = pixels whose neighbourhood
holds the background and a face. Crack pixels (`compare`): at a covered reference pixel off the
border, tessd shows the background, or a face the reference ray reaches only behind the
reference's first hit (a far face seen through a crack: found by casting that pixel's ray again
with all hits). Other id differences off the border are `mismatches`.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Tool
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from tessd.brep import ocp as brep_ocp
from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape
from tessd.brep.ocp_compat import static as _s

from png_decode import decode_png

_map_shapes = _s(TopExp, "MapShapes")
_as_face = _s(TopoDS, "Face")
_triangulation = _s(BRep_Tool, "Triangulation")
_add_optimal = _s(BRepBndLib, "AddOptimal")
_clean = _s(BRepTools, "Clean")

# The reference tessellation: linear deflection as a fraction of the bounding-box diagonal
# (issue 21: 1e-3 of the part size) and the angular deflection (radians).
REL_DEFLECTION = 1e-3
ANG_DEFLECTION = 0.05


# --------------------------------------------------------------------------------------------
# the part: document + reference mesh, in the same face order


def bounding_box(shape: Any) -> Tuple[np.ndarray, np.ndarray]:
    """The shape's tight bounding box (min corner, max corner)."""
    box = Bnd_Box()
    _add_optimal(shape, box, False, False)
    x0, y0, z0, x1, y1, z1 = box.Get()
    return np.array([x0, y0, z0]), np.array([x1, y1, z1])


def document_faces(shape: Any) -> Tuple[Dict[str, Any], List[Any]]:
    """The `tessd-brep` document the exporter makes of `shape` and the OCP faces in document
    order (face i of the list is the document's face i, id i + 1)."""
    prepared = brep_ocp.prepare(shape)
    doc = brep_ocp.export_prepared(prepared)
    m = TopTools_IndexedMapOfShape()
    _map_shapes(prepared.shape, TopAbs_FACE, m)
    faces = [_as_face(m.FindKey(i)) for i in range(1, m.Extent() + 1)]
    if len(faces) != len(doc["faces"]):
        raise AssertionError(f"{len(faces)} OCP faces but {len(doc['faces'])} document faces")
    return doc, faces


@dataclass
class RefMesh:
    """The reference triangles: vertices [N, 3], triangles [M, 3] (outward-facing order),
    face_of [M] (0-based document face index), the deflection used, faces without a mesh."""

    vertices: np.ndarray
    triangles: np.ndarray
    face_of: np.ndarray
    deflection: float
    diagonal: float
    unmeshed: List[int] = field(default_factory=list)
    _intersector: Any = None

    def intersector(self) -> Any:
        if self._intersector is None:
            import trimesh
            from trimesh.ray.ray_pyembree import RayMeshIntersector

            mesh = trimesh.Trimesh(self.vertices, self.triangles, process=False, validate=False)
            self._intersector = RayMeshIntersector(mesh)
        return self._intersector


def mesh_faces(shape: Any, faces: Sequence[Any], rel_deflection: float = REL_DEFLECTION,
               angular: float = ANG_DEFLECTION) -> RefMesh:
    """`BRepMesh_IncrementalMesh` of `shape` at `rel_deflection` × its bounding-box diagonal,
    then each face's triangulation (its location applied, reversed faces flipped), tagged with
    the face's index in `faces` (document order)."""
    lo, hi = bounding_box(shape)
    diagonal = float(np.linalg.norm(hi - lo))
    deflection = rel_deflection * diagonal
    _clean(shape)  # drop any coarser triangulation the shape carries
    BRepMesh_IncrementalMesh(shape, deflection, False, angular, False)
    verts: List[np.ndarray] = []
    tris: List[np.ndarray] = []
    owner: List[np.ndarray] = []
    unmeshed: List[int] = []
    base = 0
    for fi, face in enumerate(faces):
        loc = TopLoc_Location()
        tri = _triangulation(face, loc)
        if tri is None or tri.NbTriangles() == 0:
            unmeshed.append(fi)
            continue
        trsf = loc.Transformation()
        n = tri.NbNodes()
        pts = np.empty((n, 3))
        for i in range(1, n + 1):
            p = tri.Node(i).Transformed(trsf)
            pts[i - 1] = (p.X(), p.Y(), p.Z())
        t = np.empty((tri.NbTriangles(), 3), dtype=np.int64)
        for i in range(1, tri.NbTriangles() + 1):
            a, b, c = tri.Triangle(i).Get()
            t[i - 1] = (a - 1, b - 1, c - 1)
        if face.Orientation() == TopAbs_REVERSED:
            t = t[:, ::-1]
        verts.append(pts)
        tris.append(t + base)
        owner.append(np.full(len(t), fi, dtype=np.int64))
        base += n
    if not tris:
        raise AssertionError("BRepMesh made no triangles")
    return RefMesh(np.concatenate(verts), np.concatenate(tris), np.concatenate(owner),
                   deflection, diagonal, unmeshed)


# --------------------------------------------------------------------------------------------
# the camera and the ray cast


@dataclass(frozen=True)
class Camera:
    eye: Tuple[float, float, float]
    target: Tuple[float, float, float]
    up: Tuple[float, float, float]
    fov: float  # vertical, degrees
    width: int
    height: int

    def basis(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """forward, right, up' as the convention defines them."""
        eye, target, up = (np.asarray(v, dtype=float) for v in (self.eye, self.target, self.up))
        forward = target - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, up)
        right /= np.linalg.norm(right)
        return forward, right, np.cross(right, forward)

    def rays(self) -> Tuple[np.ndarray, np.ndarray]:
        """Per pixel (row-major, row 0 at the top): origins [H·W, 3] and the unnormalised
        directions `forward + sx·right + sy·up'` [H·W, 3]."""
        forward, right, upp = self.basis()
        w, h = self.width, self.height
        t = math.tan(math.radians(self.fov) / 2.0)
        sx = (2.0 * (np.arange(w) + 0.5) / w - 1.0) * t * w / h
        sy = (1.0 - 2.0 * (np.arange(h) + 0.5) / h) * t
        SX, SY = np.meshgrid(sx, sy)  # [H, W]
        d = forward[None, None, :] + SX[..., None] * right + SY[..., None] * upp
        d = d.reshape(-1, 3)
        o = np.broadcast_to(np.asarray(self.eye, dtype=float), d.shape).copy()
        return o, d

    def args(self) -> List[str]:
        """The tessd CLI arguments for this camera."""
        f = lambda v: ",".join(repr(float(c)) for c in v)  # noqa: E731
        return ["--size", f"{self.width}x{self.height}", "--eye", f(self.eye),
                "--target", f(self.target), "--up", f(self.up), "--fov", repr(float(self.fov))]


def fitted_camera(lo: np.ndarray, hi: np.ndarray, direction: Sequence[float], up: Sequence[float],
                  width: int, height: int, fov: float = 30.0, zoom: float = 1.0) -> Camera:
    """A camera looking at the box centre from `direction` (eye = centre + k·direction) at the
    distance where the sphere around the box fills the smaller field of view (`zoom` > 1 comes
    closer)."""
    centre = (lo + hi) / 2.0
    radius = float(np.linalg.norm(hi - lo)) / 2.0
    half_v = math.radians(fov) / 2.0
    half_h = math.atan(math.tan(half_v) * width / height)
    dist = radius / math.sin(min(half_v, half_h)) / zoom
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    eye = centre + dist * d
    return Camera(tuple(eye), tuple(centre), tuple(float(c) for c in up), fov, width, height)


@dataclass
class RefImage:
    ids: np.ndarray  # [H, W] int64, −1 background
    depth: np.ndarray  # [H, W] float64, camera z, inf background
    border: np.ndarray  # [H, W] bool
    silhouette: np.ndarray  # [H, W] bool
    camera: Camera
    mesh: RefMesh

    @property
    def covered(self) -> np.ndarray:
        return self.ids >= 0


def neighbourhood_masks(ids: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """(border, silhouette): pixels whose 3 x 3 neighbourhood (clipped at the image's edge)
    holds more than one id, and holds the background (−1) and a face."""
    p = np.pad(ids, 1, mode="edge")
    h, w = ids.shape
    shifts = [p[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    stack = np.stack(shifts)
    lo, hi = stack.min(axis=0), stack.max(axis=0)
    border = lo != hi
    silhouette = (lo < 0) & (hi >= 0)
    return border, silhouette


def raycast(mesh: RefMesh, camera: Camera) -> RefImage:
    """One ray per pixel through the reference mesh: the first hit's face id and camera z."""
    o, d = camera.rays()
    forward, _, _ = camera.basis()
    dn = d / np.linalg.norm(d, axis=1)[:, None]
    locs, ray_idx, tri_idx = mesh.intersector().intersects_location(o, dn, multiple_hits=False)
    n = camera.width * camera.height
    ids = np.full(n, -1, dtype=np.int64)
    depth = np.full(n, np.inf)
    if len(ray_idx):
        ids[ray_idx] = mesh.face_of[tri_idx]
        depth[ray_idx] = (locs - o[ray_idx]) @ forward
    ids = ids.reshape(camera.height, camera.width)
    depth = depth.reshape(camera.height, camera.width)
    border, silhouette = neighbourhood_masks(ids)
    return RefImage(ids, depth, border, silhouette, camera, mesh)


def faces_along(ref: RefImage, pixels: np.ndarray) -> List[List[Tuple[float, int]]]:
    """For pixel indices [(y, x), ...]: every hit of the pixel's ray, (camera z, face index)
    sorted by depth."""
    if len(pixels) == 0:
        return []
    o, d = ref.camera.rays()
    flat = pixels[:, 0] * ref.camera.width + pixels[:, 1]
    o, d = o[flat], d[flat]
    forward, _, _ = ref.camera.basis()
    dn = d / np.linalg.norm(d, axis=1)[:, None]
    locs, ray_idx, tri_idx = ref.mesh.intersector().intersects_location(o, dn, multiple_hits=True)
    out: List[List[Tuple[float, int]]] = [[] for _ in range(len(flat))]
    for loc, r, t in zip(locs, ray_idx, tri_idx):
        out[r].append((float((loc - o[r]) @ forward), int(ref.mesh.face_of[t])))
    for hits in out:
        hits.sort()
    return out


# --------------------------------------------------------------------------------------------
# tessd's face-id PNG


def read_rgba(path: Path) -> np.ndarray:
    """A PNG as uint8 [H, W, 4] (PIL when installed, else tests/png_decode.py)."""
    try:
        from PIL import Image
    except ImportError:
        return decode_png(Path(path).read_bytes())
    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA"), dtype=np.uint8)


def read_face_ids(path: Path) -> np.ndarray:
    """tessd's face-id PNG (index + 1 = R + 256·G + 65536·B, 0 background, A = 255) → [H, W]
    int64, the 0-based face index, −1 the background."""
    rgba = read_rgba(path).astype(np.int64)
    assert (rgba[..., 3] == 255).all(), "face-id PNG: alpha must be 255 everywhere"
    return rgba[..., 0] + 256 * rgba[..., 1] + 65536 * rgba[..., 2] - 1


# --------------------------------------------------------------------------------------------
# the comparison


@dataclass
class Comparison:
    pixels: int
    ref_covered: int
    test_covered: int
    compared: int  # covered in both, off the border
    agree: int
    mismatches: int  # off the border, both covered, ids differ, not a far face seen through a crack
    crack_background: int  # reference covered off the border, tessd background
    crack_far: int  # off the border, tessd shows a face the reference ray reaches behind its first hit
    coverage_diff: int  # coverage differs (anywhere)
    coverage_diff_off_silhouette: int
    coverage_diff_off_border: int
    crack_mask: np.ndarray = field(repr=False)
    mismatch_mask: np.ndarray = field(repr=False)

    @property
    def agreement(self) -> float:
        return self.agree / self.compared if self.compared else 0.0

    @property
    def crack_pixels(self) -> int:
        return self.crack_background + self.crack_far

    def summary(self) -> str:
        return (f"agreement {100 * self.agreement:.3f}% ({self.agree}/{self.compared}), "
                f"crack pixels {self.crack_pixels} (background {self.crack_background}, "
                f"far face {self.crack_far}), mismatches {self.mismatches}, coverage "
                f"ref {self.ref_covered} tessd {self.test_covered}, differing {self.coverage_diff} "
                f"(off silhouette {self.coverage_diff_off_silhouette}, "
                f"off border {self.coverage_diff_off_border})")


def compare(ref: RefImage, ids: np.ndarray, classify_far: bool = True) -> Comparison:
    """tessd's face ids [H, W] (−1 background) against the reference."""
    assert ids.shape == ref.ids.shape, (ids.shape, ref.ids.shape)
    off = ~ref.border
    rc, tc = ref.ids >= 0, ids >= 0
    both = rc & tc & off
    differ = both & (ids != ref.ids)
    crack_bg = rc & ~tc & off
    far = np.zeros_like(differ)
    if classify_far and differ.any():
        pix = np.argwhere(differ)
        for (y, x), hits in zip(pix, faces_along(ref, pix)):
            first = hits[0][0] if hits else math.inf
            tol = 1e-6 * ref.mesh.diagonal
            if any(fid == ids[y, x] and z > first + tol for z, fid in hits):
                far[y, x] = True
    mismatch = differ & ~far
    cov = rc != tc
    return Comparison(
        pixels=int(ids.size), ref_covered=int(rc.sum()), test_covered=int(tc.sum()),
        compared=int(both.sum()), agree=int((both & (ids == ref.ids)).sum()),
        mismatches=int(mismatch.sum()), crack_background=int(crack_bg.sum()),
        crack_far=int(far.sum()), coverage_diff=int(cov.sum()),
        coverage_diff_off_silhouette=int((cov & ~ref.silhouette).sum()),
        coverage_diff_off_border=int((cov & off).sum()),
        crack_mask=crack_bg | far, mismatch_mask=mismatch)


def compare_ids(reference_ids: np.ndarray, ids: np.ndarray) -> Tuple[float, int, int]:
    """Two face-id images without a mesh behind the first (e.g. tessd's own ray caster as the
    reference): (agreement over pixels covered in both off the first's border, pixels the first
    covers off its border that the second leaves background, coverage differences off the first's
    silhouette)."""
    border, silhouette = neighbourhood_masks(reference_ids)
    rc, tc = reference_ids >= 0, ids >= 0
    both = rc & tc & ~border
    agree = int((both & (ids == reference_ids)).sum())
    n = int(both.sum())
    return (agree / n if n else 0.0), int((rc & ~tc & ~border).sum()), int(((rc != tc) & ~silhouette).sum())


def id_colours(ids: np.ndarray) -> np.ndarray:
    """A face-id image as RGBA8 in tessd's encoding (index + 1 in R + 256·G + 65536·B): the
    reference's golden images."""
    v = (ids + 1).astype(np.int64)
    out = np.zeros(ids.shape + (4,), dtype=np.uint8)
    out[..., 0], out[..., 1], out[..., 2], out[..., 3] = v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF, 255
    return out


# --------------------------------------------------------------------------------------------
# the test harness: parts made once, figures printed at the end, golden images on request

# (test id, figures line) of every comparison made, printed at the end of the run.
FIGURES: List[Tuple[str, str]] = []


def record(name: str, line: str) -> None:
    FIGURES.append((name, line))
    print(f"\n[{name}] {line}")


@dataclass
class Part:
    name: str
    shape: Any
    doc_path: Path
    doc: Dict[str, Any]
    mesh: RefMesh
    lo: np.ndarray
    hi: np.ndarray


class Parts:
    """Parts by name, each exported and meshed once per session."""

    def __init__(self, folder: Path, builders: Dict[str, Callable[[], Any]]):
        self.folder = folder
        self.builders = builders
        self.cache: Dict[str, Part] = {}
        self.refs: Dict[Tuple[str, Camera], RefImage] = {}

    def __getitem__(self, name: str) -> Part:
        if name not in self.cache:
            shape = self.builders[name]()
            doc, faces = document_faces(shape)
            path = self.folder / f"{name}.json"
            path.write_text(json.dumps(doc))
            mesh = mesh_faces(shape, faces)
            lo, hi = bounding_box(shape)
            self.cache[name] = Part(name, shape, path, doc, mesh, lo, hi)
        return self.cache[name]

    def reference(self, name: str, camera: Camera) -> RefImage:
        key = (name, camera)
        if key not in self.refs:
            self.refs[key] = raycast(self[name].mesh, camera)
        return self.refs[key]


def save_golden(name: str, ref: RefImage, rendered: Any = None,
                comparison: Optional[Comparison] = None) -> None:
    """With $TESSD_RENDER_REF_OUT set: the reference's face-id image (tessd's encoding, the
    golden), and tessd's and a diff (red: crack, blue: mismatch, grey: border) beside it."""
    folder = os.environ.get("TESSD_RENDER_REF_OUT")
    if not folder:
        return
    from PIL import Image

    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    Image.fromarray(id_colours(ref.ids)).save(d / f"{name}_reference_ids.png")
    if rendered is not None:
        Image.fromarray(id_colours(rendered.ids)).save(d / f"{name}_tessd_ids.png")
    if comparison is not None:
        diff = np.full(ref.ids.shape + (3,), 255, dtype=np.uint8)
        diff[ref.border] = (200, 200, 200)
        diff[comparison.mismatch_mask] = (0, 0, 255)
        diff[comparison.crack_mask] = (255, 0, 0)
        Image.fromarray(diff).save(d / f"{name}_diff.png")
