"""Writes the analytic test parts (cube, cylinder, sphere) as tessd-brep JSON documents."""
import json, math, os

HERE = os.path.dirname(os.path.abspath(__file__))
TAU = 2 * math.pi


def doc(faces, edges):
    return {"format": "tessd-brep", "version": 1, "units": "mm", "faces": faces, "edges": edges}


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cube():
    # Faces: (origin, x_dir, y_dir) with x × y the outward normal; corners walk CCW in (u, v).
    planes = [
        ([0, 0, 0], [0, 1, 0], [1, 0, 0]),  # z = 0, normal -z
        ([0, 0, 1], [1, 0, 0], [0, 1, 0]),  # z = 1, normal +z
        ([0, 0, 0], [1, 0, 0], [0, 0, 1]),  # y = 0, normal -y
        ([0, 1, 0], [0, 0, 1], [1, 0, 0]),  # y = 1, normal +y
        ([0, 0, 0], [0, 0, 1], [0, 1, 0]),  # x = 0, normal -x
        ([1, 0, 0], [0, 1, 0], [0, 0, 1]),  # x = 1, normal +x
    ]
    edges = {}
    faces = []
    for fid, (o, x, y) in enumerate(planes):
        corners = [[o[i] + a * x[i] + b * y[i] for i in range(3)] for a, b in [(0, 0), (1, 0), (1, 1), (0, 1)]]
        uv = lambda p: [dot(sub(p, o), x), dot(sub(p, o), y)]
        trims = []
        for k in range(4):
            a, b = corners[k], corners[(k + 1) % 4]
            key = tuple(sorted([tuple(a), tuple(b)]))
            if key not in edges:
                s, e = [list(p) for p in key]
                edges[key] = {"id": len(edges), "curve": {"type": "line", "origin": s, "dir": sub(e, s)},
                              "range": [0.0, 1.0], "faces": []}
            edge = edges[key]
            edge["faces"].append(fid)
            s = edge["curve"]["origin"]
            e = [s[i] + edge["curve"]["dir"][i] for i in range(3)]
            us, ue = uv(s), uv(e)
            forward = list(a) == s
            trims.append({"curve": {"type": "line", "origin": us, "dir": sub(ue, us)},
                          "range": [0.0, 1.0] if forward else [1.0, 0.0], "edge": edge["id"]})
        faces.append({"id": fid, "reversed": False,
                      "surface": {"type": "plane", "origin": o, "x_dir": x, "y_dir": y},
                      "bounds": [0, 1, 0, 1], "loops": [{"edges": trims}]})
    return doc(faces, list(edges.values()))


def cylinder(r=2.0, h=3.0):
    line2 = lambda o, d, rng, e: {"curve": {"type": "line", "origin": o, "dir": d}, "range": rng, "edge": e}
    lateral = {"id": 0, "surface": {"type": "cylinder", "origin": [0, 0, 0], "x_dir": [1, 0, 0],
                                    "y_dir": [0, 1, 0], "radius": r},
               "bounds": [0, TAU, 0, h],
               "loops": [{"edges": [line2([0, 0], [1, 0], [0, TAU], 0),
                                    line2([TAU, 0], [0, 1], [0, h], 2),
                                    line2([0, h], [1, 0], [TAU, 0], 1),
                                    line2([0, 0], [0, 1], [h, 0], 2)]}]}
    bottom = {"id": 1, "surface": {"type": "plane", "origin": [0, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, -1, 0]},
              "bounds": [-r, r, -r, r],
              "loops": [{"edges": [{"curve": {"type": "circle", "center": [0, 0], "x_dir": [1, 0], "y_dir": [0, -1],
                                              "radius": r}, "range": [TAU, 0], "edge": 0}]}]}
    top = {"id": 2, "surface": {"type": "plane", "origin": [0, 0, h], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]},
           "bounds": [-r, r, -r, r],
           "loops": [{"edges": [{"curve": {"type": "circle", "center": [0, 0], "x_dir": [1, 0], "y_dir": [0, 1],
                                           "radius": r}, "range": [0, TAU], "edge": 1}]}]}
    circle3 = lambda z: {"type": "circle", "center": [0, 0, z], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0], "radius": r}
    edges = [{"id": 0, "curve": circle3(0), "range": [0, TAU], "faces": [0, 1]},
             {"id": 1, "curve": circle3(h), "range": [0, TAU], "faces": [0, 2]},
             {"id": 2, "curve": {"type": "line", "origin": [r, 0, 0], "dir": [0, 0, 1]}, "range": [0, h],
              "faces": [0]}]
    return doc([lateral, bottom, top], edges)


def sphere(r=1.5):
    q = math.pi / 2
    line2 = lambda o, d, rng, e: {"curve": {"type": "line", "origin": o, "dir": d}, "range": rng, "edge": e}
    face = {"id": 0, "surface": {"type": "sphere", "origin": [0, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0],
                                 "radius": r},
            "bounds": [0, TAU, -q, q],
            "loops": [{"edges": [line2([0, -q], [1, 0], [0, TAU], 0),
                                 line2([TAU, 0], [0, 1], [-q, q], 2),
                                 line2([0, q], [1, 0], [TAU, 0], 1),
                                 line2([0, 0], [0, 1], [q, -q], 2)]}]}
    edges = [{"id": 0, "curve": None, "range": [0, TAU], "faces": [0]},
             {"id": 1, "curve": None, "range": [0, TAU], "faces": [0]},
             {"id": 2, "curve": {"type": "circle", "center": [0, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, 0, 1],
                                 "radius": r}, "range": [-q, q], "faces": [0]}]
    return doc([face], edges)


for name, d in [("cube", cube()), ("cylinder", cylinder()), ("sphere", sphere())]:
    with open(os.path.join(HERE, name + ".json"), "w") as f:
        json.dump(d, f, indent=1)
