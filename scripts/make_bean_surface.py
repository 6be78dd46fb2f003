#!/usr/bin/env python3
"""Writes meshes/data/bean.off: the example closed surface of docs/meshes.md, a bean 60 mm
long, 30 mm wide and 24 mm high with a flat underside (where a scene fixes it), in metres.
An icosahedron subdivided 4 times (2,562 vertices, 5,120 triangles) mapped onto the bean.
Standard library only; deterministic."""
import math
import sys

def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid = {}
        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(c * c for c in p))
                v.append(tuple(c / n for c in p))
                mid[key] = len(v) - 1
            return mid[key]
        g = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    return v, f

def bean(p):
    x, y, z = p
    # An ellipsoid 30 x 15 x 12 mm (half-axes), bent in y along x, its underside flattened.
    X, Y, Z = 0.030 * x, 0.015 * y, 0.012 * z
    Y += 0.008 * (1 - x * x) - 0.004 * (1 - x * x) * (1 if y > 0 else 0) * y
    if Z < -0.008:
        Z = -0.008
    return X, Y, Z + 0.012

def main(out):
    v, f = icosphere(4)
    with open(out, "w") as o:
        o.write("OFF\n# bean: vtb's example surface (scripts/make_bean_surface.py), metres\n")
        o.write(f"{len(v)} {len(f)} 0\n")
        for p in v:
            o.write("%.9f %.9f %.9f\n" % bean(p))
        for a, b, c in f:
            o.write(f"3 {a} {b} {c}\n")

if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "meshes/data/bean.off")
