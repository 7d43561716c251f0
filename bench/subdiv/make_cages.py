#!/usr/bin/env python3
"""Write the generated cages of the subdivision benchmark as OBJ files (standard library only).

    python3 bench/subdiv/make_cages.py OUT_DIR

Writes into OUT_DIR:
  cube.obj          6 quads, 8 vertices, the cube [-1, 1]^3 (closed; symmetric about the origin)
  torus_8192.obj    128 x 64 = 8192 quads, 8192 vertices, major radius 1, minor radius 0.25
                    (closed; the reference case: OpenSubdiv 3.5 took ~351 ms of topology
                    (create + RefineUniform) to level 4 on the benchmark machines)
  torus_knot_96.obj (2,3) torus knot tube, 24 segments x 4 sides = 96 quads, 96 vertices (closed)

The shared meshes are used directly, not copied, e.g. /work/shared/data/mesh/spot_control_mesh.obj
(180 faces: quads, 4 triangles, 16 pentagons), quadknot.obj (1440 quads), suzanne.obj
(500 faces, open), fandisk.obj (triangles, for --scheme loop).
"""
import math
import os
import sys


def write_obj(path, verts, faces, comment):
    with open(path, "w") as f:
        f.write(f"# {comment}\n")
        for x, y, z in verts:
            f.write(f"v {x:.9g} {y:.9g} {z:.9g}\n")
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


def cube():
    verts = [(x, y, z) for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)]
    # index = 4*ix + 2*iy + iz; faces wound counter-clockwise seen from outside
    faces = [
        (0, 1, 3, 2),  # x = -1
        (4, 6, 7, 5),  # x = +1
        (0, 4, 5, 1),  # y = -1
        (2, 3, 7, 6),  # y = +1
        (0, 2, 6, 4),  # z = -1
        (1, 5, 7, 3),  # z = +1
    ]
    return verts, faces


def tube_faces(n_seg, n_side):
    faces = []
    for i in range(n_seg):
        i1 = (i + 1) % n_seg
        for j in range(n_side):
            j1 = (j + 1) % n_side
            faces.append((i * n_side + j, i1 * n_side + j, i1 * n_side + j1, i * n_side + j1))
    return faces


def torus(n_major=128, n_minor=64, big_r=1.0, small_r=0.25):
    verts = []
    for i in range(n_major):
        u = 2.0 * math.pi * i / n_major
        cu, su = math.cos(u), math.sin(u)
        for j in range(n_minor):
            v = 2.0 * math.pi * j / n_minor
            rr = big_r + small_r * math.cos(v)
            verts.append((rr * cu, rr * su, small_r * math.sin(v)))
    return verts, tube_faces(n_major, n_minor)


def torus_knot(p=2, q=3, n_seg=24, n_side=4, tube_r=0.4):
    """Tube of radius tube_r around the (p, q) torus knot on a torus with radii 2 and 1."""

    def curve(t):
        r = 2.0 + math.cos(q * t)
        return (r * math.cos(p * t), r * math.sin(p * t), -math.sin(q * t))

    verts = []
    for i in range(n_seg):
        t = 2.0 * math.pi * i / n_seg
        c = curve(t)
        a, b = curve(t - 1e-4), curve(t + 1e-4)
        tan = [b[k] - a[k] for k in range(3)]
        ln = math.sqrt(sum(x * x for x in tan))
        tan = [x / ln for x in tan]
        # normal: the direction from the z axis to the curve point, made orthogonal to the tangent
        rad = [c[0], c[1], 0.0]
        d = sum(rad[k] * tan[k] for k in range(3))
        nrm = [rad[k] - d * tan[k] for k in range(3)]
        ln = math.sqrt(sum(x * x for x in nrm))
        nrm = [x / ln for x in nrm]
        bin_ = [tan[1] * nrm[2] - tan[2] * nrm[1],
                tan[2] * nrm[0] - tan[0] * nrm[2],
                tan[0] * nrm[1] - tan[1] * nrm[0]]
        for j in range(n_side):
            a_ = 2.0 * math.pi * j / n_side
            ca, sa = math.cos(a_), math.sin(a_)
            verts.append(tuple(c[k] + tube_r * (ca * nrm[k] + sa * bin_[k]) for k in range(3)))
    return verts, tube_faces(n_seg, n_side)


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for name, (verts, faces), comment in (
        ("cube.obj", cube(), "cube [-1,1]^3, 6 quads"),
        ("torus_8192.obj", torus(), "torus 128 x 64 = 8192 quads, R = 1, r = 0.25"),
        ("torus_knot_96.obj", torus_knot(), "(2,3) torus knot tube, 24 segments x 4 sides = 96 quads"),
    ):
        path = os.path.join(out, name)
        write_obj(path, verts, faces, comment)
        print(f"{path}: {len(verts)} vertices, {len(faces)} faces")


if __name__ == "__main__":
    main()
