#!/usr/bin/env python3
"""Writes the STL meshes the example cases use (run once; the STL files are committed).

hopper.stl  conical hopper, top diameter 160 mm, outlet 30 mm, 100 mm high, outlet at z = 150 mm,
            in millimetres (as CAD exports usually are: the case sets unit_scale: 0.001).
drum.stl    a horizontal drum (axis y through (0, 0, 0.06) m), radius 60 mm, length 80 mm,
            closed by its two end discs, with 4 lifter bars; in millimetres.
"""
import math


def write_stl(path, triangles, name):
    with open(path, "w") as f:
        f.write(f"solid {name}\n")
        for a, b, c in triangles:
            u = [b[k] - a[k] for k in range(3)]
            v = [c[k] - a[k] for k in range(3)]
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            f.write("  facet normal {:.6e} {:.6e} {:.6e}\n    outer loop\n".format(*[x / length for x in n]))
            for p in (a, b, c):
                f.write("      vertex {:.6f} {:.6f} {:.6f}\n".format(*p))
            f.write("    endloop\n  endfacet\n")
        f.write(f"endsolid {name}\n")


def hopper(segments=48, rings=6):
    """Frustum surface, normals pointing inwards (towards the material)."""
    r_top, r_bottom, z_bottom, height = 80.0, 15.0, 150.0, 100.0
    tris = []
    for j in range(rings):
        z0, z1 = z_bottom + height * j / rings, z_bottom + height * (j + 1) / rings
        r0, r1 = r_bottom + (r_top - r_bottom) * j / rings, r_bottom + (r_top - r_bottom) * (j + 1) / rings
        for i in range(segments):
            a0, a1 = 2 * math.pi * i / segments, 2 * math.pi * (i + 1) / segments
            p00 = (r0 * math.cos(a0), r0 * math.sin(a0), z0)
            p01 = (r0 * math.cos(a1), r0 * math.sin(a1), z0)
            p10 = (r1 * math.cos(a0), r1 * math.sin(a0), z1)
            p11 = (r1 * math.cos(a1), r1 * math.sin(a1), z1)
            tris += [(p00, p11, p01), (p00, p10, p11)]
    return tris


def drum(segments=64, length_segments=4, lifters=4):
    """Closed drum with inward normals: cylinder along y, end discs, lifter bars."""
    r, half, cz = 60.0, 40.0, 60.0
    tris = []
    ring = lambda a, y, rr=r: (rr * math.cos(a), y, cz + rr * math.sin(a))
    for j in range(length_segments):
        y0, y1 = -half + 2 * half * j / length_segments, -half + 2 * half * (j + 1) / length_segments
        for i in range(segments):
            a0, a1 = 2 * math.pi * i / segments, 2 * math.pi * (i + 1) / segments
            tris += [(ring(a0, y0), ring(a1, y0), ring(a1, y1)), (ring(a0, y0), ring(a1, y1), ring(a0, y1))]
    for y, sign in ((-half, 1), (half, -1)):  # end discs, normals into the drum
        centre = (0.0, y, cz)
        for i in range(segments):
            a0, a1 = 2 * math.pi * i / segments, 2 * math.pi * (i + 1) / segments
            t = (centre, ring(a0, y), ring(a1, y))
            tris.append(t if sign < 0 else (t[0], t[2], t[1]))
    for k in range(lifters):  # thin radial plates, 12 mm high, both faces
        a = 2 * math.pi * k / lifters
        p = [ring(a, -half), ring(a, half), ring(a, half, r - 12), ring(a, -half, r - 12)]
        tris += [(p[0], p[1], p[2]), (p[0], p[2], p[3]), (p[0], p[2], p[1]), (p[0], p[3], p[2])]
    return tris


if __name__ == "__main__":
    write_stl("hopper.stl", hopper(), "hopper")
    write_stl("drum.stl", drum(), "drum")
