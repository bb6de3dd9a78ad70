"""Loading vehicle files (TOML) into SI :class:`~subenv.vehicles.vehicle.Vehicle` objects.

A vehicle file states its unit system once (``units = "us_customary"`` for ft, slug, lbf, s, or
``units = "si"``); every dimensional quantity is converted to SI here and nowhere else.
See ``subenv/vehicles/data/suboff.toml`` for the format.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from subenv import _validation as check
from subenv import units
from subenv.vehicles.vehicle import LENGTH_RANGE_M, HullOffsets, HydroCoefficients, PlaneCoefficients, Vehicle

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10 only
    # (mypy checks this branch, for python_version 3.10, where the tomli backport is a dependency; an
    # environment of a later Python lacks it.)
    import tomli as tomllib  # type: ignore[import-not-found, unused-ignore]

__all__ = ["available_vehicles", "load_vehicle", "vehicle_from_dict", "vehicle_to_toml", "write_shipped_file"]

# Dimension of every key a vehicle file may hold, by section; "-" marks non-dimensional values.
_SCHEMA: dict[str, dict[str, str]] = {
    "environment": {"water_density": "density", "gravity": "acceleration"},
    "rigid_body": {
        "length": "length",
        "weight": "force",
        "buoyancy": "force",
        "inertia_y": "inertia",
        "x_G": "length",
        "z_G": "length",
        "x_B": "length",
        "z_B": "length",
    },
    "hydrodynamics": dict.fromkeys(
        ("Z_wdot", "Z_qdot", "Z_w", "Z_q", "M_wdot", "M_qdot", "M_w", "M_q", "crossflow_drag"), "-"
    ),
    "planes": {
        "Z_delta_s": "-",
        "M_delta_s": "-",
        "Z_delta_b": "-",
        "M_delta_b": "-",
        "limit": "angle",
    },
    "hull": {"max_diameter": "length", "stations": "list", "radius_ratio": "list"},
}
# Keys that may be left out, and their value then: a vehicle without bow planes leaves out their derivatives.
_OPTIONAL = {("planes", "Z_delta_b"): 0.0, ("planes", "M_delta_b"): 0.0}
# Keys whose value must be > 0 (checked on the file's own value, so the message quotes it).
_POSITIVE = {
    ("environment", "water_density"),
    ("environment", "gravity"),
    ("rigid_body", "length"),
    ("rigid_body", "weight"),
    ("rigid_body", "buoyancy"),
    ("rigid_body", "inertia_y"),
    ("hull", "max_diameter"),
}
_TOP_LEVEL = {"name": True, "description": False, "source": False, "units": True}

# Factor from the file's unit to SI, per dimension.
_TO_SI: dict[str, dict[str, float]] = {
    "us_customary": {
        "length": units.FOOT_M,
        "force": units.POUND_FORCE_N,
        "inertia": units.SLUG_FT2_KG_M2,
        "density": units.SLUG_PER_FT3_KG_PER_M3,
        "acceleration": units.FOOT_M,
        "angle": 1.0,
        "-": 1.0,
    },
    "si": dict.fromkeys(("length", "force", "inertia", "density", "acceleration", "angle", "-"), 1.0),
}

_DATA_PACKAGE = "subenv.vehicles.data"


def available_vehicles() -> list[str]:
    """Names of the vehicles shipped with the package (``load_vehicle(name)`` accepts them)."""
    return sorted(
        p.name.removesuffix(".toml")
        for p in resources.files(_DATA_PACKAGE).iterdir()
        if p.name.endswith(".toml")
    )


def load_vehicle(name_or_path: str | os.PathLike[str]) -> Vehicle:
    """Load a vehicle by its shipped name (e.g. ``"suboff"``) or from a TOML file path.

    Parameters
    ----------
    name_or_path : str or path-like
        A name from :func:`available_vehicles`, or the path of a vehicle file in the same format
        as ``subenv/vehicles/data/suboff.toml``.

    Returns
    -------
    Vehicle
        Frozen, in SI units.

    Raises
    ------
    ValueError
        Unknown name; a path that is not a regular file or not UTF-8 TOML; a missing or unknown
        key; a value that is not a finite number or outside its allowed range; a vehicle that is not
        physically admissible or that the model cannot run (a mass matrix with added mass that is not
        positive definite, buoyancy not within a factor of 2 of the weight, centres of gravity or
        buoyancy beyond a hull length, a radius of gyration longer than the hull, stern planes without
        a critical speed, a derived quantity that overflows, a hull without area, a plane without
        effect): see :class:`~subenv.vehicles.Vehicle`. The message names the file, the field, the
        value and what is allowed.
    FileNotFoundError
        A path that does not exist.
    """
    text, origin = _read(name_or_path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"vehicle file {origin}: not valid TOML: {exc}") from exc
    return vehicle_from_dict(data, origin=origin)


def _read(name_or_path: str | os.PathLike[str]) -> tuple[str, str]:
    name = os.fspath(name_or_path)
    shipped = available_vehicles()
    if name in shipped:
        return resources.files(_DATA_PACKAGE).joinpath(f"{name}.toml").read_text("utf-8"), name
    path = Path(name)
    if path.suffix == ".toml" or path.exists() or os.sep in name:
        if not path.exists():
            raise FileNotFoundError(f"vehicle file {str(path)!r} does not exist")
        if not path.is_file():
            raise ValueError(
                f"vehicle file {str(path)!r} is not a regular file (a directory or a device): "
                "must be a TOML file"
            )
        raw = path.read_bytes()
        try:
            return raw.decode("utf-8"), str(path)
        except UnicodeDecodeError as exc:
            raise ValueError(
                f"vehicle file {str(path)!r} is not UTF-8 text (byte {raw[exc.start]:#04x} at position "
                f"{exc.start}): must be a TOML file, which is UTF-8"
            ) from None
    raise ValueError(
        f"vehicle={name!r} is unknown: must be one of {shipped} or the path of a .toml vehicle file"
    )


def vehicle_from_dict(data: Mapping[str, Any], origin: str = "<dict>") -> Vehicle:
    """Build a :class:`Vehicle` from the parsed contents of a vehicle file (see :func:`load_vehicle`)."""
    where = f"vehicle file {origin}"
    for key, required in _TOP_LEVEL.items():
        if required and key not in data:
            raise ValueError(f"{where}: missing key {key!r}")
    unknown = set(data) - set(_TOP_LEVEL) - set(_SCHEMA)
    if unknown:
        raise ValueError(
            f"{where}: unknown key(s) {sorted(unknown)}; allowed top-level keys are "
            f"{sorted(set(_TOP_LEVEL) | set(_SCHEMA))}"
        )
    unit_system = data["units"]
    if not (isinstance(unit_system, str) and unit_system in _TO_SI):
        raise ValueError(f"{where}: units={unit_system!r} is invalid: must be one of {sorted(_TO_SI)}")
    factors = _TO_SI[unit_system]

    si: dict[str, dict[str, Any]] = {}
    for section, keys in _SCHEMA.items():
        table = data.get(section)
        if not isinstance(table, Mapping):
            raise ValueError(f"{where}: missing section [{section}]")
        unknown = set(table) - set(keys)
        if unknown:
            raise ValueError(
                f"{where}: unknown key(s) {sorted(unknown)} in [{section}]; allowed keys are {sorted(keys)}"
            )
        si[section] = {}
        for key, dimension in keys.items():
            if key not in table and (section, key) not in _OPTIONAL:
                raise ValueError(f"{where}: missing key {section}.{key}")
            value = table.get(key, _OPTIONAL.get((section, key)))
            try:
                si[section][key] = _file_value(section, key, value, factors.get(dimension))
            except ValueError as exc:
                raise ValueError(f"{where}: {exc}") from None

    body, hull = si["rigid_body"], si["hull"]
    hydro = dict(si["hydrodynamics"])
    crossflow_drag = hydro.pop("crossflow_drag")
    length = body["length"]
    breadth_m = tuple(hull["max_diameter"] * r for r in hull["radius_ratio"])
    try:
        check.number(
            "length_m", length, *LENGTH_RANGE_M
        )  # (before the stations: a huge length overflows them)
        # Station convention of the thesis's offsets: x = (10 - station) L / 20, forward positive.
        x_m = tuple((10.0 - s) * length / 20.0 for s in hull["stations"])
        return Vehicle(
            name=str(data["name"]),
            description=str(data.get("description", "")),
            source=str(data.get("source", "")),
            length_m=length,
            weight_N=body["weight"],
            buoyancy_N=body["buoyancy"],
            inertia_y_kg_m2=body["inertia_y"],
            x_G_m=body["x_G"],
            z_G_m=body["z_G"],
            x_B_m=body["x_B"],
            z_B_m=body["z_B"],
            water_density_kg_m3=si["environment"]["water_density"],
            gravity_m_s2=si["environment"]["gravity"],
            hydro=HydroCoefficients(**hydro),
            planes=PlaneCoefficients(
                Z_delta_s=si["planes"]["Z_delta_s"],
                M_delta_s=si["planes"]["M_delta_s"],
                Z_delta_b=si["planes"]["Z_delta_b"],
                M_delta_b=si["planes"]["M_delta_b"],
                limit_rad=si["planes"]["limit"],
            ),
            hull=HullOffsets(x_m=x_m, breadth_m=breadth_m),
            crossflow_drag=crossflow_drag,
        )
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from exc


def _file_value(section: str, key: str, value: Any, to_si: float | None) -> Any:
    """``section.key`` of a file in SI: a finite number (> 0 for the keys of ``_POSITIVE``) times the
    factor ``to_si`` of its unit, or with ``to_si`` None a list of finite numbers. Checked before the
    conversion: an integer beyond the float range (TOML's integers have no bound) is refused by name,
    not met as an ``OverflowError``."""
    name = f"{section}.{key}"
    if to_si is None:
        ok = isinstance(value, list) and all(check.is_finite(v) for v in value)
        check.require(name, value, ok, "a list of finite numbers")
        return [float(v) for v in value]
    check.require(name, value, check.is_number(value), "a number")
    check.require(name, value, check.is_finite(value), "a finite number")
    if (section, key) in _POSITIVE:
        check.require(name, value, value > 0, "> 0")
    return float(value) * to_si


# Significant digits of the hull's stations and radius ratios in a written file: they are recovered
# from x and b by a division, so their last bits are rounding noise (station 0.1 would read
# 0.09999999999999964); 12 digits keep the file readable and the hull within 1e-12 of the vehicle's.
_HULL_DIGITS = 12


def vehicle_to_toml(vehicle: Vehicle, header: str = "") -> str:
    """Write a vehicle as the text of a vehicle file in SI units, which :func:`load_vehicle` reads back.

    Every number is written in full (``repr``), so the file loads to the same vehicle, except the hull's
    stations and radius ratios, rounded to 12 significant digits (a relative change below 1e-12).

    Parameters
    ----------
    vehicle : Vehicle
    header : str
        Comment lines for the top of the file (each starts with ``#``): where the numbers come from.
    """

    def number(value: float) -> str:
        return repr(float(value))

    def numbers(values: list[float]) -> str:
        return "[" + ", ".join(number(float(f"{v:.{_HULL_DIGITS}g}")) for v in values) + "]"

    L = vehicle.length_m
    breadth = vehicle.hull.breadth_m
    max_breadth = max(breadth)
    h, p = vehicle.hull, vehicle.planes
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    lines += [
        "",
        f"name = {json.dumps(vehicle.name)}",  # (a JSON string is a TOML basic string)
        f"description = {json.dumps(vehicle.description)}",
        f"source = {json.dumps(vehicle.source)}",
        'units = "si"  # m, kg, N, s, rad',
        "",
        "[environment]",
        f"water_density = {number(vehicle.water_density_kg_m3)}  # kg/m^3",
        f"gravity = {number(vehicle.gravity_m_s2)}  # m/s^2",
        "",
        "[rigid_body]",
        f"length = {number(L)}  # m",
        f"weight = {number(vehicle.weight_N)}  # N",
        f"buoyancy = {number(vehicle.buoyancy_N)}  # N",
        f"inertia_y = {number(vehicle.inertia_y_kg_m2)}  # kg m^2",
        f"x_G = {number(vehicle.x_G_m)}  # m",
        f"z_G = {number(vehicle.z_G_m)}  # m",
        f"x_B = {number(vehicle.x_B_m)}  # m",
        f"z_B = {number(vehicle.z_B_m)}  # m",
        "",
        "[hydrodynamics]",
        *(f"{f.name} = {number(getattr(vehicle.hydro, f.name))}" for f in dataclasses.fields(vehicle.hydro)),
        f"crossflow_drag = {number(vehicle.crossflow_drag)}",
        "",
        "[planes]",
        *(
            f"{name} = {number(getattr(p, name))}"
            for name in ("Z_delta_s", "M_delta_s", *(("Z_delta_b", "M_delta_b") if p.has_bow_planes else ()))
        ),
        *(() if p.has_bow_planes else ("# No bow planes: Z_delta_b and M_delta_b left out (0).",)),
        f"limit = {number(p.limit_rad)}  # rad",
        "",
        "[hull]",
        "# Stations: x = (10 - station) L / 20, forward positive; breadth = max_diameter * radius_ratio.",
        f"max_diameter = {number(max_breadth)}  # m",
        f"stations = {numbers([10.0 - 20.0 * x / L for x in h.x_m])}",
        f"radius_ratio = {numbers([b / max_breadth for b in breadth])}",
    ]
    return "\n".join(lines) + "\n"


def write_shipped_file(name: str, text: str, module: str, argv: list[str] | None = None) -> int:
    """The command line of a module that writes a shipped vehicle file (``python -m <module> [--check]``):
    write ``text`` as ``subenv/vehicles/data/<name>.toml``, or with ``--check`` only say whether the file
    is ``text`` (exit status 1 if not)."""
    import argparse

    parser = argparse.ArgumentParser(description=f"Write (or check) subenv/vehicles/data/{name}.toml.")
    parser.add_argument("--check", action="store_true", help="only check that the shipped file is up to date")
    args = parser.parse_args(argv)
    path = Path(str(resources.files(_DATA_PACKAGE).joinpath(f"{name}.toml")))
    if args.check:
        current = path.read_text("utf-8") if path.is_file() else None
        print(f"{path}: {'up to date' if current == text else f'OUT OF DATE: run python -m {module}'}")
        return 0 if current == text else 1
    path.write_text(text, "utf-8")
    print(f"wrote {path}")
    return 0
