"""Writes fig_10_sphere.xyz and fig_11_saddle.xyz, the samples of
scenes/fig_10_interpolation.ron and scenes/fig_11_open_interpolation.ron
(seed 000 §7, figs. 10-11): positions only (x y z per line), so the fit
estimates the normals. Run from this directory: python3 fig_10_11_points.py"""
import math


def sphere():
    """A closed surface: 400 Fibonacci points on the sphere of radius 11
    (median distance to the nearest sample 1.85)."""
    n, r = 400, 11.0
    golden = math.pi * (3 - math.sqrt(5))
    out = [
        "# Sphere of radius 11 sampled at 400 Fibonacci points (nearest sample about 1.85 units",
        "# away); x y z, no normals. scenes/fig_10_interpolation.ron (scenes/data/fig_10_11_points.py).",
    ]
    for k in range(n):
        z = 1 - (2 * k + 1) / n
        s = math.sqrt(1 - z * z)
        phi = golden * k
        out.append("%.9f %.9f %.9f" % (r * s * math.cos(phi), r * s * math.sin(phi), r * z))
    return out


def saddle():
    """An open saddle z = 0.015 (x^2 - y^2): a hexagonal lattice 2 units
    apart in x-y within radius 12 of the origin, without the samples within
    3.5 of (3, 1) (a hole wider than the search range)."""
    out = [
        "# Open saddle z = 0.015 (x^2 - y^2): hexagonal lattice 2 apart in x-y inside radius 12,",
        "# a hole of radius 3.5 about (3, 1); x y z, no normals.",
        "# scenes/fig_11_open_interpolation.ron (scenes/data/fig_10_11_points.py).",
    ]
    h = math.sqrt(3) / 2
    for j in range(-8, 9):
        for i in range(-8, 9):
            x = 2 * (i + 0.5 * (j % 2))
            y = 2 * h * j
            if math.hypot(x, y) > 12 or math.hypot(x - 3, y - 1) < 3.5:
                continue
            out.append("%.9f %.9f %.9f" % (x, y, 0.015 * (x * x - y * y)))
    return out


for name, lines in [("fig_10_sphere.xyz", sphere()), ("fig_11_saddle.xyz", saddle())]:
    with open(name, "w") as f:
        f.write("\n".join(lines) + "\n")
