"""Froude scaling: the same boat at another size, moving in the same water under the same gravity.

Riedel (1993) Ch. VI: "Since the non-dimensional Froude numbers are based on the metacentric height
and LCG-LCB separation, Froude scaling can be used to apply this analysis to full scale vessels".
Two geometrically similar boats, one ``length_ratio`` = lambda times the other, in water of the same
density under the same gravity, move alike when their Froude numbers u / sqrt(g L) are equal; then
every quantity of dimension L^a T^b M^c scales with a fixed power of lambda:

===========================  ===========  ==============================================================
quantity                     factor       why
===========================  ===========  ==============================================================
length, position, depth      lambda       geometric similarity (L, x_G, z_G, x_B, z_B, hull stations and
                                          breadths, so z_GB and x_GB too)
area                         lambda^2     geometric similarity (hull planform area A)
volume, mass, force          lambda^3     W and B are rho g V with rho, g unchanged; m = W / g
moment                       lambda^4     force x length (restoring moment z_GB W)
moment of inertia            lambda^5     mass x length^2 (I_y)
speed                        lambda^1/2   equal Froude number u / sqrt(g L) (so u_cr scales this way)
time                         lambda^1/2   length / speed
rate, eigenvalue             lambda^-1/2  1 / time (q, closed- and open-loop eigenvalues)
water density, gravity       1            the same fluid and planet: the premise of Froude similarity
non-dimensional derivatives  1            SNAME primes (Z'_w, M'_q, Z'_delta ...) depend on shape only
plane angles, limit          1            angles
cross-flow drag C_D          1            a coefficient of the shape
===========================  ===========  ==============================================================

The dimensional derivatives follow from the primes with rho/2 L^n (Riedel 1993 Appendix A), so they
scale on their own: Z_w ~ lambda^2, Z_wdot ~ lambda^3, M_qdot ~ lambda^5 and so on, consistent with
the table (Z_w u w is a force: lambda^2 * lambda^1/2 * lambda^1/2 = lambda^3).

The Reynolds number u L / nu is *not* kept: it grows as lambda^(3/2) (with the same water). The
coefficients are taken as independent of Reynolds number, as the thesis does when it recommends
Froude scaling; a real full-scale boat's viscous derivatives (Z'_w, M'_w, C_D) differ somewhat from
the model's.
"""

from __future__ import annotations

import dataclasses
from typing import Final, Literal

from subenv import _validation as check
from subenv.vehicles.vehicle import LENGTH_RANGE_M, HullOffsets, Vehicle

__all__ = ["FROUDE_EXPONENTS", "Quantity", "froude_factor", "froude_scaled"]

Quantity = Literal["length", "area", "volume", "mass", "force", "moment", "inertia", "speed", "time", "rate"]
"""A kind of quantity that :func:`froude_factor` scales."""

FROUDE_EXPONENTS: Final[dict[str, float]] = {
    "length": 1.0,
    "area": 2.0,
    "volume": 3.0,
    "mass": 3.0,
    "force": 3.0,
    "moment": 4.0,
    "inertia": 5.0,
    "speed": 0.5,
    "time": 0.5,
    "rate": -0.5,
}
"""The power of the length ratio by which each kind of quantity scales (see the module's table)."""


def _check_ratio(length_ratio: float) -> float:
    return check.positive("length_ratio", length_ratio)


def froude_factor(quantity: Quantity, length_ratio: float) -> float:
    """The factor lambda^k by which a ``quantity`` scales under Froude similarity.

    Parameters
    ----------
    quantity : str
        One of :data:`FROUDE_EXPONENTS` (``"speed"``: lambda^1/2, ``"rate"``: lambda^-1/2, ...).
    length_ratio : float
        lambda, the new length over the old, finite and > 0.

    Examples
    --------
    The critical speed of a boat 24 times longer is sqrt(24) times higher:
    ``critical_speed(froude_scaled(v, 24)) == froude_factor("speed", 24) * critical_speed(v)``.
    """
    if quantity not in FROUDE_EXPONENTS:
        raise ValueError(f"quantity={quantity!r} is invalid: must be one of {sorted(FROUDE_EXPONENTS)}")
    return _check_ratio(length_ratio) ** FROUDE_EXPONENTS[quantity]


def froude_scaled(vehicle: Vehicle, length_ratio: float, name: str | None = None) -> Vehicle:
    """The vehicle ``length_ratio`` times larger (or smaller), at equal Froude number (Riedel 1993 Ch. VI).

    Lengths scale with lambda, forces with lambda^3, the moment of inertia with lambda^5; the water,
    gravity and every non-dimensional coefficient stay (the table in :mod:`subenv.vehicles.scaling`).
    The new vehicle passes the same admissibility checks as any other.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle to scale (any loading: z_GB, x_GB and B - W scale with it).
    length_ratio : float
        lambda = new length / old length; finite, > 0, and such that the new length lies in
        :data:`~subenv.vehicles.vehicle.LENGTH_RANGE_M`.
    name : str, optional
        Name of the new vehicle; by default ``"<name>[x<lambda>]"``.

    Returns
    -------
    Vehicle
        A new vehicle; speeds of equal Froude number are sqrt(lambda) times ``vehicle``'s, times and
        1 / eigenvalues too.

    Raises
    ------
    ValueError
        ``length_ratio`` not a finite number > 0, or giving a length outside ``LENGTH_RANGE_M``.

    References
    ----------
    J. S. Riedel, *Pitchfork Bifurcations and Dive Plane Reversal of Submarines at Low Speeds*, NPS
    thesis, 1993, Ch. VI (Froude scaling to full-scale vessels) and eq. 4.25 (Fn = u / sqrt(g z_GB)).
    """
    ratio = _check_ratio(length_ratio)
    low, high = LENGTH_RANGE_M
    new_length = vehicle.length_m * ratio
    check.require(
        "length_ratio",
        length_ratio,
        low <= new_length <= high,
        f"a number giving a length in [{low}, {high}] m (LENGTH_RANGE_M): "
        f"{vehicle.name!r} is {vehicle.length_m!r} m long, so in "
        f"[{low / vehicle.length_m:.6g}, {high / vehicle.length_m:.6g}]; it gives {new_length!r} m",
    )
    length = froude_factor("length", ratio)
    force = froude_factor("force", ratio)
    hull = HullOffsets(
        x_m=tuple(x * length for x in vehicle.hull.x_m),
        breadth_m=tuple(b * length for b in vehicle.hull.breadth_m),
    )
    note = f"Froude-scaled by length ratio {ratio!r} from {vehicle.name!r} (subenv.vehicles.froude_scaled)."
    # dataclasses.replace runs every admissibility check again (ranges, the mass matrix).
    return dataclasses.replace(
        vehicle,
        name=name if name is not None else f"{vehicle.name}[x{ratio:g}]",
        description=f"{vehicle.description} {note}".strip(),
        source=vehicle.source,
        length_m=new_length,
        weight_N=vehicle.weight_N * force,
        buoyancy_N=vehicle.buoyancy_N * force,
        inertia_y_kg_m2=vehicle.inertia_y_kg_m2 * froude_factor("inertia", ratio),
        x_G_m=vehicle.x_G_m * length,
        z_G_m=vehicle.z_G_m * length,
        x_B_m=vehicle.x_B_m * length,
        z_B_m=vehicle.z_B_m * length,
        hull=hull,
    )
