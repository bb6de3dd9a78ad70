"""Vehicle data: a frozen, SI description of a submarine's vertical-plane properties.

Everything derived (mass, dimensional coefficients, hull planform area and centroid) is a
computed property, never a stored copy, so a variant made with :meth:`Vehicle.variant` can never
disagree with itself.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Final

import numpy as np

from subenv import _validation as check
from subenv._typing import ArrayLike

__all__ = [
    "BUOYANCY_RATIO_RANGE",
    "DERIVATIVE_BOUND",
    "LENGTH_RANGE_M",
    "DimensionalCoefficients",
    "HullOffsets",
    "HydroCoefficients",
    "PlaneCoefficients",
    "Vehicle",
]


DERIVATIVE_BOUND: Final = 10.0
"""The largest magnitude of a non-dimensional derivative (hydrodynamic or plane), a typo's bound.

SNAME primes are made non-dimensional by rho/2 L^n so that a hull's are of order (D/L)^2 (a sphere's
Z'_wdot is -pi/6 = -0.52) and a plane's of order its area over L^2 times its lift slope (at most 2 pi,
thin-aerofoil theory); SUBOFF's and the REMUS 100's are 1e-4 to 3e-2. A derivative of 10 would need a hull
broader than it is long or planes larger than L^2: a larger one is a slip of an exponent or a unit, and one
of 1e300 made eq. 3.9 lose its root (``M_w = -1e300`` loaded, then ``gym.make`` said the vehicle had no
critical speed)."""


@dataclass(frozen=True)
class HydroCoefficients:
    """Non-dimensional vertical-plane hydrodynamic derivatives (SNAME primes).

    Made dimensional with rho/2 L^n as in Riedel (1993) Appendix A: see
    :class:`DimensionalCoefficients`.
    """

    Z_wdot: float
    Z_qdot: float
    Z_w: float
    Z_q: float
    M_wdot: float
    M_qdot: float
    M_w: float
    M_q: float

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            check.number(
                f"hydrodynamics.{f.name}", getattr(self, f.name), -DERIVATIVE_BOUND, DERIVATIVE_BOUND
            )


@dataclass(frozen=True)
class PlaneCoefficients:
    """Non-dimensional control derivatives of the stern (s) and bow (b) planes, and their limit.

    A vehicle without bow planes (the REMUS 100 steers in pitch with its stern planes alone) has
    ``Z_delta_b = M_delta_b = 0``: :attr:`has_bow_planes` is False, and the environments refuse the
    control modes that would move them.
    """

    Z_delta_s: float
    M_delta_s: float
    Z_delta_b: float = 0.0
    M_delta_b: float = 0.0
    limit_rad: float = 0.4

    def __post_init__(self) -> None:
        for name in ("Z_delta_s", "M_delta_s"):
            value = check.number(f"planes.{name}", getattr(self, name), -DERIVATIVE_BOUND, DERIVATIVE_BOUND)
            # Each plane pair acts behind or ahead of the centre, so it makes a heave force and a pitch
            # moment; a zero derivative leaves a plane without effect (and eq. 3.9 without a critical speed).
            check.require(f"planes.{name}", value, value != 0, "a non-zero number (a plane with effect)")
        bow = [
            check.number(f"planes.{name}", getattr(self, name), -DERIVATIVE_BOUND, DERIVATIVE_BOUND)
            for name in ("Z_delta_b", "M_delta_b")
        ]
        if (bow[0] == 0) != (bow[1] == 0):  # bow planes with effect, or none at all
            name, value = ("Z_delta_b", bow[0]) if bow[0] == 0 else ("M_delta_b", bow[1])
            check.require(
                f"planes.{name}",
                value,
                False,
                "a non-zero number (a plane with effect), or 0 for both Z_delta_b and M_delta_b "
                "(no bow planes)",
            )
        limit = self.limit_rad
        check.require(
            "planes.limit_rad", limit, check.is_number(limit) and 0 < limit <= math.pi / 2, "in (0, pi/2] rad"
        )

    @property
    def has_bow_planes(self) -> bool:
        """Whether the vehicle has bow planes (non-zero bow derivatives)."""
        return self.Z_delta_b != 0


@dataclass(frozen=True)
class HullOffsets:
    """Hull planform breadth b(x) at stations x, for the cross-flow drag integral.

    ``x_m`` is measured forward from the origin (the thesis's midship, L/2), so it decreases from
    nose to tail; ``breadth_m`` is the local hull breadth. Between stations b(x) is linear.
    """

    x_m: tuple[float, ...]
    breadth_m: tuple[float, ...]

    def __post_init__(self) -> None:
        if len(self.x_m) != len(self.breadth_m):
            raise ValueError(
                f"hull offsets: {len(self.x_m)} stations but {len(self.breadth_m)} breadths; "
                "must be the same number"
            )
        if len(self.x_m) < 2:
            raise ValueError(f"hull offsets: {len(self.x_m)} stations; must be at least 2")
        x = np.asarray(self.x_m, dtype=float)
        b = np.asarray(self.breadth_m, dtype=float)
        if not np.all(np.isfinite(x)) or not np.all(np.isfinite(b)):
            raise ValueError("hull offsets: stations and breadths must be finite numbers")
        if np.any(np.diff(x) >= 0):
            raise ValueError(
                "hull offsets: x_m must decrease strictly from nose to tail (stations must increase strictly)"
            )
        if np.any(b < 0):
            raise ValueError(f"hull offsets: breadth_m has a negative value {b.min()!r}; must be >= 0")
        area = self.area_m2
        if not (math.isfinite(area) and area > 0):  # all-zero breadths: no drag and no centroid
            raise ValueError(f"hull offsets: planform area={area!r} m^2 is invalid: must be > 0 and finite")

    @cached_property  # (the analysis's residuals read it hundreds of thousands of times; frozen)
    def area_m2(self) -> float:
        """Planform area int b(x) dx, exact for the piecewise-linear hull [m^2]."""
        x = np.asarray(self.x_m)
        return (
            float(-np.trapezoid(self.breadth_m, x)) + 0.0
        )  # (+ 0.0: an all-zero hull has area 0.0, not -0.0)

    @cached_property
    def centroid_x_m(self) -> float:
        """Planform centroid int x b(x) dx / A, forward of the origin [m] (exact, piecewise linear)."""
        x = np.asarray(self.x_m)
        b = np.asarray(self.breadth_m)
        x0, x1, b0, b1 = x[:-1], x[1:], b[:-1], b[1:]
        # Exact first moment of a linear b over each segment (the trapezoid rule is not exact for x b).
        moment = np.sum((x1 - x0) * (b0 * (2 * x0 + x1) + b1 * (x0 + 2 * x1)) / 6.0)
        return float(-moment / self.area_m2)


@dataclass(frozen=True)
class DimensionalCoefficients:
    """Dimensional hydrodynamic and control derivatives in SI.

    Units: Z_w [kg/m], Z_q [kg], Z_wdot [kg], Z_qdot [kg m], M_w [kg], M_q [kg m],
    M_wdot [kg m], M_qdot [kg m^2], Z_delta_* [kg/m /rad], M_delta_* [kg /rad]; forces are
    ``Z_w u w`` [N], ``u^2 Z_delta delta`` [N] and so on (Riedel 1993 eqs 2.38-2.43).
    """

    Z_wdot: float
    Z_qdot: float
    Z_w: float
    Z_q: float
    M_wdot: float
    M_qdot: float
    M_w: float
    M_q: float
    Z_delta_s: float
    M_delta_s: float
    Z_delta_b: float
    M_delta_b: float


_POSITIVE_FIELDS = ("weight_N", "buoyancy_N", "inertia_y_kg_m2")
# The two quantities that scale every hydrodynamic derivative (rho/2 L^2 .. L^5), bounded to physical
# ranges: any water, fresh to the densest brine, with a wide margin; any hull from a 1 cm model to longer
# than any vessel afloat. Outside them the derivatives, or their products in the analysis, leave the
# floating-point range (water_density = 1e-300 made eq. 3.9 underflow; length = 1e308 overflowed).
# Gravity, which makes the mass of the weight, from a moon's subsurface ocean (Enceladus, 0.11 m/s^2) to ten
# times the Earth's.
LENGTH_RANGE_M: Final = (0.01, 1000.0)
"""The lengths a vehicle may have [m]."""
_RANGES = {"water_density_kg_m3": (500.0, 2000.0), "length_m": LENGTH_RANGE_M, "gravity_m_s2": (0.1, 100.0)}
BUOYANCY_RATIO_RANGE: Final = (0.5, 2.0)
"""The buoyancy a vehicle may have, as a multiple B / W of its weight.

The model is a submerged vehicle near neutral trim: W - B is an imperfection of the pitchfork (Riedel 1993
Ch. V.C; the scenarios' excess buoyancy is at most 1e-3 W), and no submerged vehicle is twice as heavy or
as light as the water it displaces. Within a factor of 2, B - W is exact in floating point (Sterbenz's
lemma), so a loading that keeps W and sets B - W (:meth:`Vehicle.variant`, every scenario's draw) gives B
back exactly: ``weight = 1e30`` (lbf) made B - W round to -W and every reset's buoyancy 0."""
# The centres of gravity and buoyancy lie within the vehicle: |x| <= L / 2 from midship, |z| within the hull's
# radius (or a sail's height). Within a hull length of the origin, with a margin of 2 at least.
_POSITION_MAX_LENGTHS: Final = 1.0
# The radius of gyration sqrt(I_y / m) of a body whose mass lies within its length is below L / 2 (SUBOFF's
# and the REMUS 100's are 0.24 L and 0.25 L): one beyond L is an inertia in the wrong unit or a typo.
_RADIUS_OF_GYRATION_MAX_LENGTHS: Final = 1.0
# Checked fields that enter the mass matrix (the hydrodynamic derivatives do too, but never change).
_MASS_MATRIX_FIELDS = frozenset({*_RANGES, "weight_N", "inertia_y_kg_m2", "x_G_m"})
_CHECKED_FIELDS = (*_RANGES, *_POSITIVE_FIELDS, "x_G_m", "z_G_m", "x_B_m", "z_B_m", "crossflow_drag")


@dataclass(frozen=True)
class Vehicle:
    """A submarine's vertical-plane model data, in SI units (m, kg, N, s, rad).

    Load one with :func:`subenv.load_vehicle`; make variants with :meth:`variant`.

    Positions are body axes with the origin at midship: x forward, z down. Pitch is positive
    nose-up, depth positive down.

    Made (and varied), a vehicle is checked for what the model needs: every field finite and in its
    range (:data:`LENGTH_RANGE_M`, water density, gravity; |derivatives| <= :data:`DERIVATIVE_BOUND`;
    G and B within a hull length of midship), B / W in :data:`BUOYANCY_RATIO_RANGE`, a positive-definite
    mass matrix and a radius of gyration within the length, finite derived quantities, and stern planes
    with a critical speed (eq. 3.9). Whether a loading has one (z_GB > 0) is the loading's: a scenario
    may set z_GB, and only scenarios with speeds relative to the critical speed need one.
    """

    name: str
    length_m: float
    weight_N: float
    buoyancy_N: float
    inertia_y_kg_m2: float
    x_G_m: float
    z_G_m: float
    x_B_m: float
    z_B_m: float
    water_density_kg_m3: float
    gravity_m_s2: float
    hydro: HydroCoefficients
    planes: PlaneCoefficients
    hull: HullOffsets
    crossflow_drag: float
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        self._check(_CHECKED_FIELDS)
        self._check_stern_planes_reverse()

    def _check(self, names: Iterable[str]) -> None:
        """Validate the fields ``names`` (of :data:`_CHECKED_FIELDS`), then what they enter: the ratio of
        buoyancy to weight, the mass matrix and the radius of gyration, the derived quantities."""
        names = tuple(names)
        for name in names:
            value = getattr(self, name)
            if name in _RANGES:
                check.number(name, value, *_RANGES[name])
            elif name in _POSITIVE_FIELDS:
                check.positive(name, value)
            elif name == "crossflow_drag":
                check.non_negative(name, value)
            else:  # a centre of gravity or buoyancy: within the vehicle
                check.number(
                    name, value, -_POSITION_MAX_LENGTHS * self.length_m, _POSITION_MAX_LENGTHS * self.length_m
                )
        if {"weight_N", "buoyancy_N"} & set(names):
            low, high = BUOYANCY_RATIO_RANGE
            ratio = self.buoyancy_N / self.weight_N
            if not low <= ratio <= high:
                raise ValueError(
                    f"weight_N={self.weight_N!r} and buoyancy_N={self.buoyancy_N!r} are invalid: B / W = "
                    f"{ratio:.6g} must be in [{low}, {high}] (a submerged vehicle near neutral trim)"
                )
        self._check_derived()
        if not _MASS_MATRIX_FIELDS.isdisjoint(names):
            self._check_mass_matrix()
            k = math.sqrt(self.inertia_y_kg_m2 / self.mass_kg)
            check.require(
                "inertia_y_kg_m2",
                self.inertia_y_kg_m2,
                k <= _RADIUS_OF_GYRATION_MAX_LENGTHS * self.length_m,
                f"at most mass_kg * length_m^2 = {self.mass_kg * self.length_m**2:.6g} kg m^2 (a radius of "
                f"gyration sqrt(I_y / m) = {k:.6g} m within the length {self.length_m!r} m)",
            )

    def _check_derived(self) -> None:
        """The derived quantities the model uses must be finite: finite fields can overflow in a product."""
        W, B = self.weight_N, self.buoyancy_N
        (m11, m12), (m21, m22) = self.mass_matrix
        for formula, value, inputs in (
            ("mass_kg = W / g", self.mass_kg, ("weight_N", "gravity_m_s2")),
            ("z_GB_m = z_G - z_B", self.z_GB_m, ("z_G_m", "z_B_m")),
            ("x_GB_m = x_G - x_B", self.x_GB_m, ("x_G_m", "x_B_m")),
            (
                "the hydrostatic moment z_G W - z_B B (eq. 2.39)",
                self.z_G_m * W - self.z_B_m * B,
                ("z_G_m", "weight_N", "z_B_m", "buoyancy_N"),
            ),
            (
                "the hydrostatic moment x_G W - x_B B (eq. 2.39)",
                self.x_G_m * W - self.x_B_m * B,
                ("x_G_m", "weight_N", "x_B_m", "buoyancy_N"),
            ),
            (
                "the mass matrix's determinant Dv (eqs 2.59-2.68)",
                m11 * m22 - m12 * m21,
                ("weight_N", "gravity_m_s2", "inertia_y_kg_m2", "x_G_m"),
            ),
        ):
            if not math.isfinite(value):
                given = ", ".join(f"{name}={getattr(self, name)!r}" for name in inputs)
                raise ValueError(f"{formula} = {value!r} with {given} is invalid: must be finite")

    def _check_stern_planes_reverse(self) -> None:
        """The stern planes must have a critical speed for a statically stable loading.

        Riedel (1993) eq. 3.9, u_cr^2 = z_GB B Z_delta / (M_w Z_delta - Z_w M_delta), has a root for
        z_GB > 0 only if Z_delta / (M_w Z_delta - Z_w M_delta) > 0: for planes behind the point where the
        hull's heave force acts (x = -M_w / Z_w), as stern planes are. This is the vehicle's alone (its hull
        and its planes; the loading, which scenarios change, enters as z_GB B > 0), and every scenario whose
        speeds are relative to the critical speed needs it. Checked on the primes (rho/2 L^n > 0).
        """
        h, p = self.hydro, self.planes
        coupling = h.M_w * p.Z_delta_s - h.Z_w * p.M_delta_s
        if p.Z_delta_s * coupling > 0:
            return
        ratio = p.Z_delta_s / coupling if coupling else math.inf
        raise ValueError(
            f"hydrodynamics.Z_w={h.Z_w!r} and M_w={h.M_w!r} with planes.Z_delta_s={p.Z_delta_s!r} and "
            f"M_delta_s={p.M_delta_s!r} give the stern planes no critical speed: Z_delta_s / (M_w Z_delta_s "
            f"- Z_w M_delta_s) = {ratio:.6g} must be > 0 (Riedel 1993 eq. 3.9: stern planes act behind the "
            "hull's centre of heave force, x = -M_w / Z_w). Check the signs: sources differ in convention"
        )

    def _check_mass_matrix(self) -> None:
        """The mass matrix must be positive definite: kinetic energy > 0 for every motion (w, q)."""
        (m11, m12), (m21, m22) = self.mass_matrix
        # Sylvester's criterion on the symmetric part (a non-symmetric M is positive definite when it is).
        symmetric = 0.5 * (m12 + m21)
        if m11 > 0 and m11 * m22 - symmetric * symmetric > 0:  # (a product overflows to inf, ** raises)
            return
        h = self.hydro
        raise ValueError(
            f"hydrodynamics.Z_wdot={h.Z_wdot!r}, Z_qdot={h.Z_qdot!r}, M_wdot={h.M_wdot!r}, "
            f"M_qdot={h.M_qdot!r} with mass_kg={self.mass_kg!r}, inertia_y_kg_m2={self.inertia_y_kg_m2!r} "
            f"and x_G_m={self.x_G_m!r} give the vertical-plane mass matrix [[{m11:.6g}, {m12:.6g}], "
            f"[{m21:.6g}, {m22:.6g}]] (SI): it must be positive definite (the body and the water it moves "
            "have positive kinetic energy)"
        )

    # --- derived quantities -------------------------------------------------------------
    @property
    def mass_kg(self) -> float:
        """Mass m = W / g [kg]."""
        return self.weight_N / self.gravity_m_s2

    @property
    def z_GB_m(self) -> float:
        """Metacentric height z_GB = z_G - z_B [m] (positive: G below B, statically stable)."""
        return self.z_G_m - self.z_B_m

    @property
    def x_GB_m(self) -> float:
        """Ballast offset x_GB = x_G - x_B [m] (Riedel 1993 Ch. IV)."""
        return self.x_G_m - self.x_B_m

    @property
    def excess_buoyancy_N(self) -> float:
        """Excess buoyancy B - W [N] (positive: light; models near-surface suction, Ch. V.C)."""
        return self.buoyancy_N - self.weight_N

    @cached_property
    def coefficients(self) -> DimensionalCoefficients:
        """Dimensional derivatives, nd_k = rho/2 L^(k+1) (Riedel 1993 Appendix A, THESIS1.M)."""
        half_rho = 0.5 * self.water_density_kg_m3
        L = self.length_m
        nd1, nd2, nd3, nd4 = (half_rho * L**k for k in (2, 3, 4, 5))
        h, p = self.hydro, self.planes
        return DimensionalCoefficients(
            Z_wdot=nd2 * h.Z_wdot,
            Z_qdot=nd3 * h.Z_qdot,
            Z_w=nd1 * h.Z_w,
            Z_q=nd2 * h.Z_q,
            M_wdot=nd3 * h.M_wdot,
            M_qdot=nd4 * h.M_qdot,
            M_w=nd2 * h.M_w,
            M_q=nd3 * h.M_q,
            Z_delta_s=nd1 * p.Z_delta_s,
            M_delta_s=nd2 * p.M_delta_s,
            Z_delta_b=nd1 * p.Z_delta_b,
            M_delta_b=nd2 * p.M_delta_b,
        )

    @property
    def mass_matrix(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Rigid-body plus added mass of the heave and pitch equations, the matrix of (wdot, qdot).

        Riedel (1993) eqs 2.38-2.39: ``[[m - Z_wdot, -(Z_qdot + m x_G)], [-(M_wdot + m x_G), I_y - M_qdot]]``,
        in ``[[kg, kg m], [kg m, kg m^2]]``. Positive definite for every vehicle (checked when made).
        """
        c, m = self.coefficients, self.mass_kg
        return (
            (m - c.Z_wdot, -(c.Z_qdot + m * self.x_G_m)),
            (-(c.M_wdot + m * self.x_G_m), self.inertia_y_kg_m2 - c.M_qdot),
        )

    @property
    def hull_area_m2(self) -> float:
        """Hull planform area A [m^2]."""
        return self.hull.area_m2

    @property
    def hull_centroid_x_m(self) -> float:
        """Hull planform centroid x_A, forward of midship [m]."""
        return self.hull.centroid_x_m

    # --- variants -----------------------------------------------------------------------
    def loading_fields(
        self,
        *,
        z_GB_m: ArrayLike | None = None,
        x_GB_m: ArrayLike | None = None,
        excess_buoyancy_N: ArrayLike | None = None,
        crossflow_drag: ArrayLike | None = None,
    ) -> dict[str, Any]:
        """The fields a loading sets (:meth:`variant`'s parameters; None leaves a field as it is), unchecked.

        Each value may be an array, one loading per element (a vector environment's resets): its
        fields are then arrays too, each element computed as for a variant with that loading.

        Returns
        -------
        dict
            ``z_G_m`` (G moved, B kept), ``x_G_m``, ``buoyancy_N`` (B changed, W kept) and
            ``crossflow_drag``, those of them that the loading sets.
        """
        fields: dict[str, Any] = {}
        if z_GB_m is not None:
            fields["z_G_m"] = self.z_B_m + z_GB_m
        if x_GB_m is not None:
            fields["x_G_m"] = self.x_B_m + x_GB_m
        if excess_buoyancy_N is not None:
            fields["buoyancy_N"] = self.weight_N + excess_buoyancy_N
        if crossflow_drag is not None:
            fields["crossflow_drag"] = crossflow_drag
        return fields

    def check_loadings(
        self,
        *,
        z_GB_m: ArrayLike | None = None,
        x_GB_m: ArrayLike | None = None,
        excess_buoyancy_N: ArrayLike | None = None,
        crossflow_drag: ArrayLike | None = None,
    ) -> None:
        """Check loadings of this vehicle as :meth:`variant` checks one: the same ``ValueError`` for any
        that is invalid.

        Parameters
        ----------
        z_GB_m, x_GB_m, excess_buoyancy_N, crossflow_drag : float or ndarray, optional
            As :meth:`variant`'s, an array of one loading per element (None: the field is not set).
            Every loading within the box their ranges span is checked.

        Notes
        -----
        Each quantity :meth:`variant` checks is monotone in each field of the loading (G's position and
        B in their ranges, B / W, the hydrostatic moments) or, the mass matrix's, a parabola in x_G
        whose least (the definiteness) or largest (the determinant) value on an interval lies at an
        end. So the box passes when its corners do: :meth:`variant` is made at each (at most 16).
        """
        names: list[str] = []
        ends: list[list[float]] = []
        loading = {
            "z_GB_m": z_GB_m,
            "x_GB_m": x_GB_m,
            "excess_buoyancy_N": excess_buoyancy_N,
            "crossflow_drag": crossflow_drag,
        }
        for name, value in loading.items():
            if value is not None:
                names.append(name)
                ends.append(sorted({float(np.min(value)), float(np.max(value))}))  # (nan: variant refuses it)
        for corner in itertools.product(*ends):
            fields: dict[str, Any] = dict(zip(names, corner, strict=True))
            self.variant(**fields)

    def variant(
        self,
        *,
        z_GB_m: float | None = None,
        x_GB_m: float | None = None,
        excess_buoyancy_N: float | None = None,
        crossflow_drag: float | None = None,
        name: str | None = None,
    ) -> Vehicle:
        """Return a copy with another loading, leaving this vehicle unchanged.

        Parameters
        ----------
        z_GB_m : float, optional
            Metacentric height z_G - z_B [m]; moves G, keeps B.
        x_GB_m : float, optional
            Ballast offset x_G - x_B [m] (Riedel 1993 Ch. IV); moves G, keeps B.
        excess_buoyancy_N : float, optional
            B - W [N] (Riedel 1993 Ch. V.C); changes B, keeps W (and so the mass).
        crossflow_drag : float, optional
            Hull cross-flow drag coefficient C_D (>= 0).
        name : str, optional
            Name of the variant; by default the base name with the changes appended.
        """
        labels = []
        if z_GB_m is not None:
            z_GB_m = check.number("z_GB_m", z_GB_m)
            labels.append(f"z_GB={z_GB_m:g}m")
        if x_GB_m is not None:
            x_GB_m = check.number("x_GB_m", x_GB_m)
            labels.append(f"x_GB={x_GB_m:g}m")
        if excess_buoyancy_N is not None:
            excess_buoyancy_N = check.number("excess_buoyancy_N", excess_buoyancy_N)
            labels.append(f"B-W={excess_buoyancy_N:g}N")
        if crossflow_drag is not None:
            crossflow_drag = check.non_negative("crossflow_drag", crossflow_drag)
            labels.append(f"C_D={crossflow_drag:g}")
        changes = self.loading_fields(
            z_GB_m=z_GB_m, x_GB_m=x_GB_m, excess_buoyancy_N=excess_buoyancy_N, crossflow_drag=crossflow_drag
        )
        if not changes and name is None:
            return self
        changes["name"] = name if name is not None else f"{self.name}[{','.join(labels)}]"
        # A copy with the changed fields set and checked: the others were checked when this vehicle
        # was made, and the cached dimensional derivatives stay valid, as the loading (G, B, C_D)
        # does not enter them. (An environment makes a variant at every reset of a scenario with a
        # random loading; dataclasses.replace would check and derive everything again.)
        vehicle = copy.copy(self)
        for field_name, value in changes.items():
            object.__setattr__(vehicle, field_name, value)
        vehicle._check(field for field in changes if field in _CHECKED_FIELDS)  # (not "name")
        return vehicle
