"""Writes fig_15_cylinder.xyz and fig_15_spheroid.xyz (scenes/fig_15_spin*.ron):
a cylinder and a prolate spheroid sampled about one unit apart, tilted so that
the particles' initial local x axes are not aligned with the principal
directions. Run from this directory: python3 fig_15_shapes.py"""
import math

H = math.sqrt(3) / 2


def rot_from_z(axis):
    """Rotation (Rodrigues) taking +z to the unit vector along `axis`."""
    ax = [a / math.sqrt(sum(b * b for b in axis)) for a in axis]
    v = [-ax[1], ax[0], 0.0]
    s = math.sqrt(sum(c * c for c in v))
    c = ax[2]
    k = [vi / s for vi in v]

    def rotate(p):
        kxp = [k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]]
        kdp = sum(k[i] * p[i] for i in range(3))
        return [p[i] * c + kxp[i] * s + k[i] * kdp * (1 - c) for i in range(3)]

    return rotate


def line(p, n):
    return " ".join("%.12f" % v for v in p + n)


def cylinder():
    rotate = rot_from_z([0.3, 0.5, 1.0])
    out = [
        "# Cylinder of radius 3 and length 12 about the axis (0.3, 0.5, 1)/|.|, centred at the origin:",
        "# rings sqrt(3)/2 apart, 19 particles each, alternate rings shifted half a step;",
        "# x y z nx ny nz (outward normals). scenes/fig_15_spin.ron (scenes/data/fig_15_shapes.py).",
    ]
    r, n, rings = 3.0, 19, 15
    for j in range(rings):
        z = (j - (rings - 1) / 2) * H
        for i in range(n):
            phi = 2 * math.pi * (i + 0.5 * (j % 2)) / n
            p = [r * math.cos(phi), r * math.sin(phi), z]
            out.append(line(rotate(p), rotate([math.cos(phi), math.sin(phi), 0.0])))
    return out


def spheroid():
    a, c = 3.0, 6.0
    rotate = rot_from_z([-0.4, 0.2, 1.0])
    steps = 20000
    ts = [math.pi * k / steps for k in range(steps + 1)]
    s = [0.0]
    for k in range(1, steps + 1):
        t0, t1 = ts[k - 1], ts[k]
        s.append(s[-1] + math.hypot(a * (math.sin(t1) - math.sin(t0)), c * (math.cos(t1) - math.cos(t0))))
    rings = max(2, round(s[-1] / H))
    step = s[-1] / rings
    out = [
        "# Prolate spheroid x^2/9 + y^2/9 + z^2/36 = 1 with its long axis along (-0.4, 0.2, 1)/|.|:",
        "# rings about sqrt(3)/2 apart in meridian arc length, round(2 pi rho) particles each, alternate",
        "# rings shifted half a step; x y z nx ny nz (outward normals). scenes/fig_15_spin.ron (scenes/data/fig_15_shapes.py).",
    ]
    k = 0
    for j in range(rings + 1):
        while k < steps and s[k] < j * step:
            k += 1
        rho, z = a * math.sin(ts[k]), c * math.cos(ts[k])
        m = max(1, round(2 * math.pi * rho))
        for i in range(m):
            phi = 2 * math.pi * (i + 0.5 * (j % 2)) / m
            p = [rho * math.cos(phi), rho * math.sin(phi), z]
            nn = [p[0] / a**2, p[1] / a**2, p[2] / c**2]
            norm = math.sqrt(sum(q * q for q in nn))
            out.append(line(rotate(p), rotate([q / norm for q in nn])))
    return out


for name, rows in [("fig_15_cylinder.xyz", cylinder()), ("fig_15_spheroid.xyz", spheroid())]:
    with open(name, "w") as f:
        f.write("\n".join(rows) + "\n")
