"""The free surface's slender-body theory against exact potential flow: a check, not a benchmark of speed.

    .venv/bin/python benchmarks/free_surface_panel.py [--panels 80 24] [--quick] [--spheroid]

An independent 3-D computation of the potential flow past the hull: a source-panel method (constant
source density on flat quadrilaterals, point sources beyond three panel sizes, 6 x 6 sub-points nearer;
Hess and Smith 1967, "Calculation of potential flow about arbitrary bodies", Prog. Aero. Sci. 8), the
rigid lid by image panels, the loads by Lagally's theorem on the panels' sources in the flow of
everything but the hull's own panels (the onset stream, an outer source, the images). It prints the
tables of docs/free_surface.md:

1. Munk's moment on a prolate spheroid (L/D = 8) at a small incidence, against Lamb's coefficients: the
   panels' own accuracy (a few percent at these resolutions, falling slowly with more panels);
2. a hull in the non-uniform flow of an outer point source (no free surface, no incidence): the moment
   against the three candidate slender-body forms (sources alone; with u int a_33 w dx; with
   u int (rho S + a_33) w dx, :func:`subenv.dynamics.free_surface.section_load`);
3. SUBOFF (and with ``--spheroid`` a spheroid of its length and diameter) under the rigid lid in level
   flight (pitch theta, stream horizontal): the heave force and the pitch derivatives against
   :func:`subenv.dynamics.free_surface.suction` (both theories), the deep-water moment (Munk's) taken
   away.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from subenv.dynamics.free_surface import SOURCES_ONLY, section_load, suction
from subenv.dynamics.hull import HullTable, slender_points
from subenv.vehicles import load_vehicle

RHO = 1000.0
NEAR = 3.0  # panel sizes within which a panel's influence is summed over sub-points
SUB = 6  # sub-points per side of a panel there


def mesh(x_m, breadth_m, n_axial: int, n_around: int) -> tuple[np.ndarray, ...]:
    """Panels of the hull of revolution: centroids, outward normals, areas, corners (x forward, z up)."""
    order = np.argsort(x_m)
    x, r = np.asarray(x_m, float)[order], 0.5 * np.asarray(breadth_m, float)[order]
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(r)))])
    s = arc[-1] * 0.5 * (1 - np.cos(np.linspace(0.0, math.pi, n_axial + 1)))  # denser at the ends
    xs, rs = np.interp(s, arc, x), np.interp(s, arc, r)
    rs[0] = rs[-1] = 0.0
    phi = np.linspace(0.0, 2 * math.pi, n_around + 1)
    P = np.stack([xs[:, None] + 0 * phi, rs[:, None] * np.cos(phi), rs[:, None] * np.sin(phi)], -1)
    p00, p10, p11, p01 = P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]
    n = np.cross(p01 - p10, p11 - p00)
    area = 0.5 * np.linalg.norm(n, axis=-1)
    keep = area.ravel() > 1e-14
    corners = np.stack([p00, p10, p11, p01], -2).reshape(-1, 4, 3)[keep]
    return corners.mean(1), (n / (2 * area[..., None])).reshape(-1, 3)[keep], area.ravel()[keep], corners


def placed(panels, pitch: float, depth: float) -> tuple[np.ndarray, ...]:
    """The panels pitched nose-up by ``pitch`` about midship, midship ``depth`` below z = 0."""
    c, s = math.cos(pitch), math.sin(pitch)
    R, down = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]), np.array([0.0, 0.0, -depth])
    centre, normal, area, corners = panels
    return centre @ R.T + down, normal @ R.T, area, corners @ R.T + down


def influence(points, centre, area, corners, mirrored: bool, rows=400):
    """Velocity at ``points`` per unit source density on each panel (or its mirror image in z = 0)."""
    if mirrored:
        centre, corners = centre * [1, 1, -1], corners * [1, 1, -1]
    u = (np.arange(SUB) + 0.5) / SUB
    a, b = (m.ravel() for m in np.meshgrid(u, u, indexing="ij"))
    weights = np.stack([(1 - a) * (1 - b), a * (1 - b), a * b, (1 - a) * b], -1)  # bilinear corners
    for start in range(0, len(points), rows):
        p = points[start : start + rows]
        d = p[:, None] - centre[None]
        r2 = np.maximum((d * d).sum(-1), 1e-100)  # (a panel on its own centroid: replaced below)
        K = area[None, :, None] * d / (4 * math.pi * r2[..., None] ** 1.5)
        i, j = np.nonzero(r2 < NEAR * NEAR * area[None])
        sub = np.einsum("qc,mck->mqk", weights, corners[j])
        dd = p[i][:, None] - sub
        near = (area[j, None, None] / SUB**2 * dd / (4 * math.pi * (dd * dd).sum(-1)[..., None] ** 1.5)).sum(
            1
        )
        near[(i + start == j) & (not mirrored)] = 0.0  # (a flat panel's own tangential velocity)
        K[i, j] = near
        yield slice(start, start + len(p)), K


def loads(panels, pitch: float, depth: float, lid: bool, outer=None) -> tuple[float, float]:
    """(heave force up [N], nose-up moment about midship [N m]) at unit speed (stream -x)."""
    centre, normal, area, corners = placed(panels, pitch, depth)
    onset = np.tile([-1.0, 0.0, 0.0], (len(centre), 1)) + (outer(centre) if outer else 0.0)
    A = np.empty((len(centre),) * 2)
    for rows, K in influence(centre, centre, area, corners, False):
        A[rows] = np.einsum("ijk,ik->ij", K, normal[rows])
    np.fill_diagonal(A, 0.5)
    if lid:
        for rows, K in influence(centre, centre, area, corners, True):
            A[rows] += np.einsum("ijk,ik->ij", K, normal[rows])
    sigma = np.linalg.solve(A, -(normal * onset).sum(1))
    outside = onset.copy()
    if lid:
        for rows, K in influence(centre, centre, area, corners, True):
            outside[rows] += np.einsum("ijk,j->ik", K, sigma)
    F = -RHO * (sigma * area)[:, None] * outside  # Lagally: -rho Q V on each panel's source
    arm_x, arm_z = centre[:, 0], centre[:, 2] + depth
    return float(F[:, 2].sum()), float((arm_x * F[:, 2] - arm_z * F[:, 0]).sum())


def spheroid(slenderness: float) -> tuple[np.ndarray, np.ndarray]:
    x = np.linspace(-1.0, 1.0, 2001)
    return x, 2.0 / slenderness * np.sqrt(np.clip(1 - x * x, 0.0, None))


def munk(n_axial: int, n_around: int) -> None:
    x, b = spheroid(8.0)
    e = math.sqrt(1 - 1 / 64)
    log = math.log((1 + e) / (1 - e))
    a0, b0 = 2 * (1 - e * e) / e**3 * (0.5 * log - e), 1 / e**2 - (1 - e * e) / (2 * e**3) * log
    pitch, volume = 0.05, 4 / 3 * math.pi / 64
    lamb = (b0 / (2 - b0) - a0 / (2 - a0)) * RHO * volume * math.sin(pitch) * math.cos(pitch)
    _, panel = loads(mesh(x, b, n_axial, n_around), pitch, 50.0, lid=False)
    print(
        f"1. Munk's moment, spheroid L/D 8, 0.05 rad: panels {panel:.4g} N m, Lamb {lamb:.4g} "
        f"({panel / lamb - 1:+.1%})"
    )


def outer_source(n_axial: int, n_around: int) -> None:
    print("2. Moment in an outer source's flow [N m]: panels | sources alone | + a_33 | + (rho S + a_33)")
    cases = {
        "spheroid L/D 8": (spheroid(8.0), 0.01, [(0.0, 0.5), (0.6, 0.4), (-0.8, 0.3)]),
        "SUBOFF": (
            (load_vehicle("suboff").hull.x_m, load_vehicle("suboff").hull.breadth_m),
            0.05,
            [(0.0, 1.0), (1.5, 0.8), (-1.5, 0.8)],
        ),
    }
    for name, ((x, b), strength, places) in cases.items():
        order = np.argsort(x)
        axis = slender_points(np.asarray(x, float)[order], np.asarray(b, float)[order])
        panels = mesh(x, b, n_axial, n_around)
        _, still = loads(panels, 0.0, 50.0, lid=False)
        for px, pz in places:
            where = np.array([px, 0.0, -50.0 + pz])

            def flow(p, where=where, strength=strength):
                d = p - where
                return strength * d / (4 * math.pi * (d * d).sum(-1)[:, None] ** 1.5)

            _, panel = loads(panels, 0.0, 50.0, lid=False, outer=flow)
            v = flow(np.stack([axis[0], 0 * axis[0], -50.0 + 0 * axis[0]], -1))
            parts = [
                section_load(xk, sk, vk, 0.0, 1.0, vn, ve, 0.0)
                for (xk, sk, vk, _), vn, ve in zip(axis.T, v[:, 2], v[:, 0], strict=True)
            ]
            alone = RHO * sum(xk * (-sk * vn) for (xk, sk, _, _), vn in zip(axis.T, v[:, 2], strict=True))
            full = RHO * sum(m for _, m in parts)
            print(
                f"   {name}, source at x {px:+.1f} m, {pz:.1f} m above: {panel - still:.4g} | {alone:.4g} | "
                f"{0.5 * (alone + full):.4g} | {full:.4g}"
            )


def rigid_lid(n_axial: int, n_around: int, name: str, x_m, breadth_m, depths) -> None:
    """The hull (stations ``x_m``, breadths ``breadth_m``) under the rigid lid in level flight."""
    panels = mesh(x_m, breadth_m, n_axial, n_around)
    hull = HullTable.from_offsets(tuple(x_m), tuple(breadth_m))
    pitch = 0.02
    deep = {s: loads(panels, s * pitch, 50.0, lid=False) for s in (-1, 1)}
    print(
        f"3. {name} in level flight at 1 m/s: Z [N, up] at 0 rad, dZ/dtheta, dM/dtheta [per rad], "
        "deep taken away:"
    )
    for h in depths:
        near = {s: loads(panels, s * pitch, h, lid=True) for s in (-1, 0, 1)}
        dZ = ((near[1][0] - deep[1][0]) - (near[-1][0] - deep[-1][0])) / (2 * pitch)
        dM = ((near[1][1] - deep[1][1]) - (near[-1][1] - deep[-1][1])) / (2 * pitch)
        cells = [f"panels {near[0][0]:.4g}, {dZ:.4g}, {dM:.4g}"]
        for theory, model in (("slender body", 0.0), ("sources only", SOURCES_ONLY)):

            def at(t, model=model, h=h):  # level flight: the stream horizontal, w = sin(theta) in body axes
                Z, M = suction(hull, t, h, math.cos(t), RHO, math.sin(t), 0.0, model)
                return -float(Z), float(M)

            (z0, _), (zp, mp), (zm, mm) = at(0.0), at(pitch), at(-pitch)
            cells.append(f"{theory} {z0:.4g}, {(zp - zm) / (2 * pitch):.4g}, {(mp - mm) / (2 * pitch):.4g}")
        print(f"   h = {h} m: " + " | ".join(cells))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--panels", type=int, nargs=2, default=(80, 24), metavar=("AXIAL", "AROUND"))
    parser.add_argument("--quick", action="store_true", help="the rigid lid at 1 m only")
    parser.add_argument("--spheroid", action="store_true", help="the rigid lid on a spheroid too")
    args = parser.parse_args()
    munk(*args.panels)
    outer_source(*args.panels)
    suboff = load_vehicle("suboff")
    rigid_lid(
        *args.panels,
        "SUBOFF",
        suboff.hull.x_m,
        suboff.hull.breadth_m,
        (1.0,) if args.quick else (2.0, 1.0, 0.5),
    )
    if args.spheroid:
        # SUBOFF's length and diameter (L/D 8.4), a smooth nose
        x = np.linspace(-2.13, 2.13, 2001)
        breadth = 0.508 * np.sqrt(np.clip(1 - (x / 2.13) ** 2, 0.0, None))
        rigid_lid(
            *args.panels, "a spheroid of SUBOFF's length and diameter", x, breadth, (3.0, 1.5, 1.0, 0.7)
        )


if __name__ == "__main__":
    main()
