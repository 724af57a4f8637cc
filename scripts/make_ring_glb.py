#!/usr/bin/python3
"""Make scenes/assets/ring.glb: a closed thin cylindrical band standing on z = 0.

Inner wall radius 0.5 m (the mirror surface that draws the cardioid, Shah et al. 2007 Fig. 12), wall
thickness 0.01 m, height 0.25 m, 256 segments. Four parts, each with its own vertices so that edges
stay sharp: inner wall (normals towards the axis), outer wall (normals away from it), top and bottom
rims (normals +z / -z). Triangles are counter-clockwise seen from outside the solid band.

  /usr/bin/python3 scripts/make_ring_glb.py scenes/assets/ring.glb [--radius 0.5] [--thickness 0.01]
      [--height 0.25] [--segments 256]
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402  (obj_to_glb reports a missing numpy clearly)
from obj_to_glb import signed_volume, write_glb  # noqa: E402


def ring(radius, thickness, height, segments):
    positions, normals, triangles = [], [], []

    def add_quad_strip(points_a, points_b, normals_a, normals_b, flip):
        """Quads between two closed rings of points (a: first row, b: second row)."""
        base = len(positions)
        n = len(points_a)
        positions.extend(points_a + points_b)
        normals.extend(normals_a + normals_b)
        for k in range(n):
            k1 = (k + 1) % n
            a0, a1, b0, b1 = base + k, base + k1, base + n + k, base + n + k1
            if flip:
                triangles.extend([[a0, b1, a1], [a0, b0, b1]])
            else:
                triangles.extend([[a0, a1, b1], [a0, b1, b0]])

    angles = [2 * math.pi * k / segments for k in range(segments)]
    ring_at = lambda r, z: [[r * math.cos(a), r * math.sin(a), z] for a in angles]  # noqa: E731
    radial = [[math.cos(a), math.sin(a), 0.0] for a in angles]
    inward = [[-x, -y, 0.0] for x, y, _ in radial]
    up, down = [[0.0, 0.0, 1.0]] * segments, [[0.0, 0.0, -1.0]] * segments
    r_in, r_out = radius, radius + thickness
    # Outer wall: bottom row -> top row, counter-clockwise seen from outside.
    add_quad_strip(ring_at(r_out, 0.0), ring_at(r_out, height), radial, radial, flip=False)
    # Inner wall: seen from the axis, so the opposite order.
    add_quad_strip(ring_at(r_in, 0.0), ring_at(r_in, height), inward, inward, flip=True)
    # Top rim (seen from +z): inner row -> outer row.
    add_quad_strip(ring_at(r_in, height), ring_at(r_out, height), up, up, flip=True)
    # Bottom rim (seen from -z).
    add_quad_strip(ring_at(r_in, 0.0), ring_at(r_out, 0.0), down, down, flip=False)
    return np.array(positions), np.array(normals), np.array(triangles, dtype=np.int64)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("glb")
    ap.add_argument("--radius", type=float, default=0.5)
    ap.add_argument("--thickness", type=float, default=0.01)
    ap.add_argument("--height", type=float, default=0.25)
    ap.add_argument("--segments", type=int, default=256)
    args = ap.parse_args()
    p, n, t = ring(args.radius, args.thickness, args.height, args.segments)
    write_glb(args.glb, p, n, t, name="ring")
    exact = math.pi * ((args.radius + args.thickness) ** 2 - args.radius ** 2) * args.height
    print(f"{args.glb}: {len(p)} vertices, {len(t)} triangles, signed volume {signed_volume(p, t):.6g} m^3 "
          f"(smooth band {exact:.6g})")


if __name__ == "__main__":
    main()
