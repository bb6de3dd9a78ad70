"""Pygame rendering of the dive-plane environment: a side view of the hull and a depth trace.

The module is self-contained: it knows nothing about the environment, only about a
:class:`Frame`, a frozen, SI description of what one picture shows. Rendering follows
Gymnasium's classic-control environments: everything is drawn on a :class:`pygame.Surface`;
``rgb_array`` output is a copy of its pixels as a ``(height, width, 3)`` ``uint8`` array
(:func:`render_rgb`) and ``human`` output blits the same picture to a window
(:class:`HumanWindow`).

Picture layout (see :func:`panel_rects`): the side-view panel is on top (or on the left when
the picture is at least twice as wide as it is tall) and the depth-trace panel below (or on
the right).

* Side view: the camera follows the hull, whose origin (midship) is fixed in the panel with
  the nose to the right. The hull outline is the polygon of the offsets (upper edge
  ``+breadth/2``, lower edge ``-breadth/2``) rotated by the pitch, so a nose-up pitch raises the
  nose. Stern planes (at ``x = -0.45 L``) and bow planes (at ``x = +0.35 L``) are short
  segments rotated by ``pitch + plane angle``: a positive plane angle turns the leading edge up
  (trailing edge down), the same sense as a nose-up pitch. Faint horizontal lines mark whole
  depths, the commanded depth is a dashed line and the water surface (depth 0) is a line with
  the sky above it when it is in view. A text header gives time, speed, critical speed, depth,
  commanded depth, pitch and plane angles.
* Depth trace: depth against time, depth increasing downward, with the commanded depth as a
  dashed line of a distinct colour, inside an axes box with ticks.

pygame is imported lazily, so importing this module never needs it; every function that
draws raises :class:`gymnasium.error.DependencyNotInstalled` when it is missing. Text uses
``pygame.font`` when it is available and is silently left out otherwise. Drawing is
deterministic: the same :class:`Frame` and size always give the same pixels.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Final

import numpy as np
import numpy.typing as npt
from typing_extensions import Self

from subenv.extras import missing_extra_message

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pygame

__all__ = [
    "BACKGROUND_RGB",
    "COMMAND_RGB",
    "DEPTH_RGB",
    "HULL_RGB",
    "PLANE_RGB",
    "SURFACE_RGB",
    "Frame",
    "HumanWindow",
    "panel_rects",
    "render_rgb",
]

RGB = tuple[int, int, int]
Rect = tuple[int, int, int, int]
"""``(left, top, width, height)`` in pixels."""

# Colours. Filled shapes and data lines are drawn without antialiasing, so pixels of these
# colours are exact and can be found in the output (the tests rely on it).
HULL_RGB: Final[RGB] = (52, 58, 70)
"""Fill colour of the hull polygon."""
HULL_EDGE_RGB: Final[RGB] = (20, 22, 28)
PLANE_RGB: Final[RGB] = (236, 132, 24)
"""Colour of the stern and bow planes."""
WATER_RGB: Final[RGB] = (178, 210, 232)
GRID_RGB: Final[RGB] = (156, 190, 216)
GRID_LABEL_RGB: Final[RGB] = (96, 132, 164)
SKY_RGB: Final[RGB] = (238, 243, 249)
SURFACE_RGB: Final[RGB] = (16, 78, 170)
"""Colour of the water-surface line in the side view."""
BACKGROUND_RGB: Final[RGB] = (255, 255, 255)
"""Background of the depth-trace panel."""
AXES_RGB: Final[RGB] = (40, 40, 40)
TICK_GRID_RGB: Final[RGB] = (228, 228, 228)
DEPTH_RGB: Final[RGB] = (24, 92, 210)
"""Colour of the depth trace."""
COMMAND_RGB: Final[RGB] = (214, 36, 36)
"""Colour of the commanded depth (dashed), in both panels."""
TEXT_RGB: Final[RGB] = (15, 15, 20)
SEPARATOR_RGB: Final[RGB] = (120, 120, 120)

_STERN_PLANE_X: Final = -0.45
"""Stern-plane position as a fraction of the hull length (forward positive)."""
_BOW_PLANE_X: Final = 0.35
"""Bow-plane position as a fraction of the hull length (forward positive)."""
_PLANE_CHORD: Final = 0.1
"""Drawn plane chord as a fraction of the hull length."""
_PLANE_THICKNESS: Final = 0.015
"""Drawn plane thickness as a fraction of the hull length (at least 3 px)."""
_GRID_MIN_PX: Final = 45.0
"""Smallest spacing of the side view's depth grid lines."""
_SURFACE_MARGIN_PX: Final = 12.0
"""Gap kept between the water surface and the header, and between the hull and the panel edge,
while the side-view camera keeps the surface in view."""
_SURFACE_RAMP: Final = 1.0
"""Depth range, in units of the panel's half height, over which the camera recentres the hull
once the surface can no longer be kept in view."""
_FIT_PITCH_RAD: Final = 0.6
"""The side view's scale keeps the hull inside its panel up to this pitch."""
_DASH_ON_PX: Final = 9.0
_DASH_OFF_PX: Final = 6.0
_FONT_SIZE: Final = 18
_MIN_SIZE: Final = 32


# --------------------------------------------------------------------------------------------
# Frame
# --------------------------------------------------------------------------------------------


def _as_float_tuple(name: str, values: Iterable[Any]) -> tuple[float, ...]:
    try:
        return tuple(float(v) for v in np.asarray(values, dtype=float).ravel())
    except (TypeError, ValueError) as exc:
        raise ValueError(f"Frame.{name} must be a sequence of numbers: {exc}") from None


@dataclass(frozen=True)
class Frame:
    """What one picture shows (all SI).

    Sequences (lists, numpy arrays, ...) given for the tuple fields are converted to tuples of
    floats, and numpy scalars to floats, so a frame is hashable and immutable.

    Attributes
    ----------
    hull_x_m : tuple of float
        Hull stations in metres, forward positive (any order; usually nose first).
    hull_breadth_m : tuple of float
        Hull breadth (diameter) at each station, in metres, ``>= 0``.
    length_m : float
        Hull length in metres, ``> 0``; places and sizes the planes.
    pitch_rad : float
        Pitch angle, nose-up positive.
    depth_m : float
        Depth of the hull's origin (midship), positive down; the surface is at 0.
    depth_command_m : float
        Commanded depth, positive down. May be nan (not drawn).
    stern_plane_rad, bow_plane_rad : float
        Plane angles; positive turns the leading edge up, like a nose-up pitch.
    speed_mps : float
        Forward speed.
    critical_speed_mps : float
        Critical speed; may be nan (shown as ``n/a``).
    time_s : float
        Simulation time.
    times_s, depths_m, commands_m : tuple of float
        Ordered history for the depth trace, all the same length (possibly empty). Non-finite
        entries are left out of the lines (they break them).

    Raises
    ------
    ValueError
        If the hull offsets are not two or more finite ``(x, breadth >= 0)`` pairs, the length
        is not finite and positive, a state value (pitch, depth, planes, speed, time) is not
        finite, or the histories differ in length.
    """

    hull_x_m: tuple[float, ...]
    hull_breadth_m: tuple[float, ...]
    length_m: float
    pitch_rad: float
    depth_m: float
    depth_command_m: float
    stern_plane_rad: float
    bow_plane_rad: float
    speed_mps: float
    critical_speed_mps: float
    time_s: float
    times_s: tuple[float, ...] = ()
    depths_m: tuple[float, ...] = ()
    commands_m: tuple[float, ...] = ()

    @classmethod
    def of(
        cls, vehicle: Any, state: Any, episode: Any, history: Sequence[tuple[float, float, float]] = ()
    ) -> Frame:
        """The frame of a sub-environment: its vehicle, its records
        (:data:`~subenv.envs.transition.STATE_DTYPE`, :data:`~subenv.envs.transition.EPISODE_DTYPE`)
        and its (time, depth, ordered depth) history."""
        times, depths, commands = zip(*history, strict=True) if history else ((), (), ())
        return cls(
            hull_x_m=vehicle.hull.x_m,
            hull_breadth_m=vehicle.hull.breadth_m,
            length_m=vehicle.length_m,
            pitch_rad=state["pitch_rad"],
            depth_m=state["depth_m"],
            depth_command_m=episode["depth_command_m"],
            stern_plane_rad=state["stern_plane_rad"],
            bow_plane_rad=state["bow_plane_rad"],
            speed_mps=state["speed_mps"],
            critical_speed_mps=episode["critical_speed_mps"],
            time_s=state["time_s"],
            times_s=times,
            depths_m=depths,
            commands_m=commands,
        )

    def __post_init__(self) -> None:
        sequences = ("hull_x_m", "hull_breadth_m", "times_s", "depths_m", "commands_m")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in sequences:
                converted: Any = _as_float_tuple(f.name, value)
            else:
                try:
                    converted = float(value)
                except (TypeError, ValueError):
                    raise ValueError(f"Frame.{f.name}={value!r} must be a number") from None
            object.__setattr__(self, f.name, converted)

        if len(self.hull_x_m) != len(self.hull_breadth_m) or len(self.hull_x_m) < 2:
            raise ValueError(
                "Frame.hull_x_m and Frame.hull_breadth_m must have the same length >= 2, got "
                f"{len(self.hull_x_m)} and {len(self.hull_breadth_m)}"
            )
        if not all(math.isfinite(v) for v in self.hull_x_m + self.hull_breadth_m):
            raise ValueError("Frame hull offsets must be finite")
        if min(self.hull_breadth_m) < 0:
            raise ValueError("Frame.hull_breadth_m must be >= 0")
        if not (math.isfinite(self.length_m) and self.length_m > 0):
            raise ValueError(f"Frame.length_m={self.length_m!r} must be finite and > 0")
        for name in (
            "pitch_rad",
            "depth_m",
            "stern_plane_rad",
            "bow_plane_rad",
            "speed_mps",
            "time_s",
        ):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"Frame.{name}={getattr(self, name)!r} must be finite")
        n = len(self.times_s)
        if len(self.depths_m) != n or len(self.commands_m) != n:
            raise ValueError(
                "Frame.times_s, Frame.depths_m and Frame.commands_m must have the same length, "
                f"got {n}, {len(self.depths_m)} and {len(self.commands_m)}"
            )


# --------------------------------------------------------------------------------------------
# pygame access
# --------------------------------------------------------------------------------------------


def _import_pygame() -> Any:
    """Import pygame, or raise Gymnasium's ``DependencyNotInstalled``."""
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    try:
        import pygame
    except ImportError as exc:
        from gymnasium.error import DependencyNotInstalled

        raise DependencyNotInstalled(missing_extra_message("render", "rendering")) from exc
    return pygame


def _load_font(pg: Any) -> Any | None:
    """The default pygame font at :data:`_FONT_SIZE`, or None if fonts are unavailable."""
    try:
        pg.font.init()
        return pg.font.Font(None, _FONT_SIZE)
    except Exception:  # missing font module, SDL_ttf failure, ...: draw without text
        return None


# --------------------------------------------------------------------------------------------
# Layout and small helpers
# --------------------------------------------------------------------------------------------


def _check_size(width: int, height: int) -> tuple[int, int]:
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"{name} must be an int, got {type(value).__name__}")
        if value < _MIN_SIZE:
            raise ValueError(f"{name}={value} must be >= {_MIN_SIZE}")
    return int(width), int(height)


def panel_rects(width: int = 720, height: int = 480) -> tuple[Rect, Rect]:
    """Where the two panels are in a picture of the given size.

    Parameters
    ----------
    width, height : int
        Picture size in pixels (each ``>= 32``).

    Returns
    -------
    side, trace : tuple of int
        ``(left, top, width, height)`` of the side-view panel and of the depth-trace panel.
        The panels are stacked (side view on top) unless ``width >= 2 * height``, when they are
        side by side (side view on the left).
    """
    width, height = _check_size(width, height)
    if width >= 2 * height:
        side_w = round(0.55 * width)
        return (0, 0, side_w, height), (side_w, 0, width - side_w, height)
    side_h = round(0.56 * height)
    return (0, 0, width, side_h), (0, side_h, width, height - side_h)


def _nice_step(span: float, target: int) -> float:
    """A 1-2-5 step giving about ``target`` intervals over ``span`` (> 0)."""
    raw = span / max(target, 1)
    magnitude = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * magnitude >= raw * (1 - 1e-9):
            return m * magnitude
    return 10.0 * magnitude  # pragma: no cover - the loop always returns


def _ticks(lo: float, hi: float, step: float) -> list[float]:
    """Multiples of ``step`` in ``[lo, hi]``."""
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    return [k * step for k in range(first, last + 1)]


def _format_tick(value: float, step: float) -> str:
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step < 1 else 0
    text = f"{value:.{decimals}f}"
    return "0" if text in ("-0", "-0.0", "-0.00", "-0.000") else text


def _fmt_signed(value: float, decimals: int = 1) -> str:
    text = f"{value:+.{decimals}f}"
    return "+" + text[1:] if float(text) == 0.0 else text


def _blit_text(
    surface: pygame.Surface,
    font: Any | None,
    text: str,
    pos: tuple[float, float],
    colour: RGB = TEXT_RGB,
    anchor: str = "topleft",
) -> None:
    """Draw ``text`` with ``pos`` at the given anchor of its box; nothing without a font."""
    if font is None:
        return
    image = font.render(text, True, colour)
    rect = image.get_rect(**{anchor: (round(pos[0]), round(pos[1]))})
    surface.blit(image, rect)


def _dashed_polyline(
    surface: pygame.Surface,
    pg: Any,
    colour: RGB,
    points: Sequence[tuple[float, float]],
    width: int,
) -> None:
    """Draw a dashed polyline, the dash pattern running on across vertices."""
    period = _DASH_ON_PX + _DASH_OFF_PX
    travelled = 0.0
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        seg = math.hypot(x1 - x0, y1 - y0)
        if seg == 0.0:
            continue
        s = 0.0
        while s < seg:
            phase = (travelled + s) % period
            if phase < _DASH_ON_PX:
                e = min(seg, s + _DASH_ON_PX - phase)
                a, b = s / seg, e / seg
                pg.draw.line(
                    surface,
                    colour,
                    (x0 + a * (x1 - x0), y0 + a * (y1 - y0)),
                    (x0 + b * (x1 - x0), y0 + b * (y1 - y0)),
                    width,
                )
                s = e
            else:
                s = min(seg, s + period - phase)
        travelled += seg


def _finite_runs(xs: Sequence[float], ys: Sequence[float]) -> list[list[tuple[float, float]]]:
    """Split ``(x, y)`` pairs into runs of consecutive finite points."""
    runs: list[list[tuple[float, float]]] = []
    current: list[tuple[float, float]] = []
    for x, y in zip(xs, ys, strict=True):
        if math.isfinite(x) and math.isfinite(y):
            current.append((x, y))
        elif current:
            runs.append(current)
            current = []
    if current:
        runs.append(current)
    return runs


# --------------------------------------------------------------------------------------------
# Side view
# --------------------------------------------------------------------------------------------


def _camera_depth(depth_m: float, half_view_m: float, surface_margin_m: float, hull_margin_m: float) -> float:
    """The depth shown at the side view's vertical centre.

    Deep down the camera follows the hull, which stays centred. Near the surface the camera
    stops rising once the surface is ``surface_margin_m`` below the top of the view and the
    hull moves down the view instead, so the surface stays in sight as long as the hull can be
    kept ``hull_margin_m`` inside the view; deeper still the hull glides back to the centre
    over a ramp of ``_SURFACE_RAMP * half_view_m``. The result is continuous in ``depth_m``.

    Parameters
    ----------
    depth_m : float
        Depth of the hull's origin.
    half_view_m : float
        Depth range from the view's centre to its top (and to its bottom).
    surface_margin_m : float
        Wanted gap between the top of the view and the surface.
    hull_margin_m : float
        Smallest allowed distance from the hull's origin to the bottom of the view.

    Returns
    -------
    float
        The camera depth.
    """
    pinned = half_view_m - surface_margin_m  # camera depth with the surface pinned at the top
    max_offset = max(0.0, half_view_m - hull_margin_m)  # largest hull offset below the centre
    ramp = _SURFACE_RAMP * half_view_m
    if depth_m <= pinned:
        offset = 0.0
    elif depth_m <= pinned + max_offset:
        offset = depth_m - pinned
    elif ramp > 0 and depth_m <= pinned + max_offset + ramp:
        offset = max_offset * (1.0 - (depth_m - pinned - max_offset) / ramp)
    else:
        offset = 0.0
    return depth_m - offset


def _draw_side_view(surface: pygame.Surface, pg: Any, font: Any | None, frame: Frame) -> None:
    """Draw the side view on ``surface`` (the panel's own surface, origin at its corner)."""
    pw, ph = surface.get_size()
    x = np.asarray(frame.hull_x_m)
    b = np.asarray(frame.hull_breadth_m)
    order = np.argsort(-x, kind="stable")  # nose first
    x, half = x[order], 0.5 * b[order]
    extent = max(frame.length_m, float(x.max() - x.min()))

    header_h = 2 * (_FONT_SIZE - 2) + 6 if font is not None else 4
    fit_h = extent * math.sin(_FIT_PITCH_RAD) + float(b.max())
    scale = max(1e-6, min(0.62 * pw / extent, 0.85 * max(ph - header_h, 1) / fit_h))
    cx = 0.5 * pw - 0.5 * (x.max() + x.min()) * scale
    cy = header_h + 0.5 * (ph - header_h)  # screen row of the camera's depth
    c, s = math.cos(frame.pitch_rad), math.sin(frame.pitch_rad)
    hull_half_height = float(np.max(np.abs(x * s) + half * c))
    camera_depth = _camera_depth(
        frame.depth_m,
        half_view_m=(cy - header_h) / scale,
        surface_margin_m=_SURFACE_MARGIN_PX / scale,
        hull_margin_m=hull_half_height + _SURFACE_MARGIN_PX / scale,
    )
    hull_y = cy + (frame.depth_m - camera_depth) * scale  # screen row of the hull's origin

    def depth_to_y(depth: float) -> float:
        return cy + (depth - camera_depth) * scale

    # Water, and the sky above the surface when it is in view.
    surface.fill(WATER_RGB)
    y_surface = depth_to_y(0.0)
    if y_surface > 0:
        pg.draw.rect(surface, SKY_RGB, (0, 0, pw, min(math.ceil(y_surface), ph)))

    # Whole-depth grid lines (labelled at the right edge), drawn under everything else.
    lo, hi = camera_depth - cy / scale, camera_depth + (ph - cy) / scale
    step = _nice_step(_GRID_MIN_PX / scale, 1)
    for d in _ticks(lo, hi, step):
        if d <= 0:
            continue
        y = round(depth_to_y(d))
        if header_h <= y < ph:
            pg.draw.line(surface, GRID_RGB, (0, y), (pw - 1, y), 1)
            _blit_text(
                surface, font, f"{_format_tick(d, step)} m", (pw - 4, y - 1), GRID_LABEL_RGB, "bottomright"
            )

    # Commanded depth.
    if math.isfinite(frame.depth_command_m):
        y_command = depth_to_y(frame.depth_command_m)
        if -2 <= y_command <= ph + 2:
            _dashed_polyline(surface, pg, COMMAND_RGB, [(0, y_command), (pw - 1, y_command)], 2)

    # Water surface.
    if 0 <= y_surface < ph:
        pg.draw.line(surface, SURFACE_RGB, (0, round(y_surface)), (pw - 1, round(y_surface)), 2)

    # Hull: body frame (x forward, z up) -> world (rotated by pitch, nose-up positive) ->
    # screen (y down).
    def to_screen(bx: float, bz: float) -> tuple[float, float]:
        return cx + (bx * c - bz * s) * scale, hull_y - (bx * s + bz * c) * scale

    outline = [to_screen(xi, hi_) for xi, hi_ in zip(x, half, strict=True)]
    outline += [to_screen(xi, -hi_) for xi, hi_ in zip(x[::-1], half[::-1], strict=True)]
    pg.draw.polygon(surface, HULL_RGB, outline)
    pg.draw.polygon(surface, HULL_EDGE_RGB, outline, 1)

    # Planes: short segments centred on the hull axis, rotated by pitch + plane angle.
    chord = _PLANE_CHORD * frame.length_m * scale
    plane_w = max(3, round(_PLANE_THICKNESS * frame.length_m * scale))
    for frac, angle in ((_STERN_PLANE_X, frame.stern_plane_rad), (_BOW_PLANE_X, frame.bow_plane_rad)):
        px, py = to_screen(frac * frame.length_m, 0.0)
        a = frame.pitch_rad + angle
        dx, dy = 0.5 * chord * math.cos(a), -0.5 * chord * math.sin(a)
        pg.draw.line(surface, PLANE_RGB, (px - dx, py - dy), (px + dx, py + dy), plane_w)

    # Header text.
    if font is not None:
        pg.draw.rect(surface, SKY_RGB, (0, 0, pw, header_h))
        crit = f"{frame.critical_speed_mps:.2f} m/s" if math.isfinite(frame.critical_speed_mps) else "n/a"
        cmd = f"{frame.depth_command_m:.2f} m" if math.isfinite(frame.depth_command_m) else "n/a"
        line1 = (
            f"t {frame.time_s:.1f} s    speed {frame.speed_mps:.2f} m/s    "
            f"critical {crit}    depth {frame.depth_m:.2f} m (command {cmd})"
        )
        line2 = (
            f"pitch {_fmt_signed(math.degrees(frame.pitch_rad))} deg    "
            f"stern plane {_fmt_signed(math.degrees(frame.stern_plane_rad))} deg    "
            f"bow plane {_fmt_signed(math.degrees(frame.bow_plane_rad))} deg"
        )
        _blit_text(surface, font, line1, (6, 3))
        _blit_text(surface, font, line2, (6, 3 + _FONT_SIZE - 2))
        pg.draw.line(surface, SEPARATOR_RGB, (0, header_h - 1), (pw - 1, header_h - 1), 1)


# --------------------------------------------------------------------------------------------
# Depth trace
# --------------------------------------------------------------------------------------------


def _trace_limits(frame: Frame) -> tuple[float, float, float, float]:
    """``(t_lo, t_hi, depth_top, depth_bottom)`` of the trace axes."""
    times = [t for t in frame.times_s if math.isfinite(t)]
    t_lo = min(times, default=frame.time_s)
    t_hi = max(max(times, default=frame.time_s), frame.time_s)
    if not t_hi - t_lo >= 1.0:
        t_hi = t_lo + 1.0

    values = [v for v in frame.depths_m + frame.commands_m if math.isfinite(v)]
    values.append(frame.depth_m)
    if math.isfinite(frame.depth_command_m):
        values.append(frame.depth_command_m)
    d_lo, d_hi = min(values), max(values)
    pad = max(0.08 * (d_hi - d_lo), 0.5)
    return t_lo, t_hi, d_lo - pad, d_hi + pad


def _draw_trace(surface: pygame.Surface, pg: Any, font: Any | None, frame: Frame) -> None:
    """Draw the depth trace on ``surface`` (the panel's own surface, origin at its corner)."""
    pw, ph = surface.get_size()
    surface.fill(BACKGROUND_RGB)
    pg.draw.line(surface, SEPARATOR_RGB, (0, 0), (pw - 1, 0), 1)
    pg.draw.line(surface, SEPARATOR_RGB, (0, 0), (0, ph - 1), 1)

    text = font is not None
    left = min(56 if text else 10, pw // 4)
    right = min(14, pw // 8)
    top = min(24 if text else 10, ph // 4)
    bottom = min(34 if text else 10, ph // 4)
    ax_w, ax_h = max(pw - left - right, 1), max(ph - top - bottom, 1)

    t_lo, t_hi, d_top, d_bot = _trace_limits(frame)

    def to_screen(t: float, d: float) -> tuple[float, float]:
        return (
            left + (t - t_lo) / (t_hi - t_lo) * (ax_w - 1),
            top + (d - d_top) / (d_bot - d_top) * (ax_h - 1),
        )

    # Grid, ticks and labels.
    n_t = max(2, ax_w // 90)
    n_d = max(2, ax_h // 32)
    t_step, d_step = _nice_step(t_hi - t_lo, n_t), _nice_step(d_bot - d_top, n_d)
    for t in _ticks(t_lo, t_hi, t_step):
        sx = round(to_screen(t, d_top)[0])
        pg.draw.line(surface, TICK_GRID_RGB, (sx, top), (sx, top + ax_h - 1), 1)
        pg.draw.line(surface, AXES_RGB, (sx, top + ax_h - 1), (sx, top + ax_h + 3), 1)
        _blit_text(surface, font, _format_tick(t, t_step), (sx, top + ax_h + 4), anchor="midtop")
    for d in _ticks(d_top, d_bot, d_step):
        sy = round(to_screen(t_lo, d)[1])
        pg.draw.line(surface, TICK_GRID_RGB, (left, sy), (left + ax_w - 1, sy), 1)
        pg.draw.line(surface, AXES_RGB, (left - 4, sy), (left, sy), 1)
        _blit_text(surface, font, _format_tick(d, d_step), (left - 6, sy), anchor="midright")
    _blit_text(surface, font, "time [s]", (left + ax_w / 2, ph - 2), anchor="midbottom")
    _blit_text(surface, font, "depth [m]", (left, top - 4), anchor="bottomleft")

    # Data, clipped to the inside of the axes box.
    clip = pg.Rect(left, top, ax_w, ax_h)
    surface.set_clip(clip)
    for run in _finite_runs(frame.times_s, frame.depths_m):
        pts = [to_screen(t, d) for t, d in run]
        if len(pts) >= 2:
            pg.draw.lines(surface, DEPTH_RGB, False, pts, 2)
        else:
            pg.draw.circle(surface, DEPTH_RGB, pts[0], 2)
    for run in _finite_runs(frame.times_s, frame.commands_m):
        pts = [to_screen(t, d) for t, d in run]
        if len(pts) >= 2:
            _dashed_polyline(surface, pg, COMMAND_RGB, pts, 2)
        else:
            pg.draw.circle(surface, COMMAND_RGB, pts[0], 2)
    surface.set_clip(None)

    pg.draw.rect(surface, AXES_RGB, clip, 1)

    # Legend, top right above the box.
    if font is not None:
        x_end = left + ax_w
        y_mid = top / 2
        for label, colour, dashed in (("command", COMMAND_RGB, True), ("depth", DEPTH_RGB, False)):
            image = font.render(label, True, TEXT_RGB)
            x_text = x_end - image.get_width()
            surface.blit(image, image.get_rect(midleft=(round(x_text), round(y_mid))))
            x0, x1 = x_text - 30, x_text - 6
            if dashed:
                _dashed_polyline(surface, pg, colour, [(x0, y_mid), (x1, y_mid)], 2)
            else:
                pg.draw.line(surface, colour, (x0, y_mid), (x1, y_mid), 2)
            x_end = x0 - 14


# --------------------------------------------------------------------------------------------
# Public entry points
# --------------------------------------------------------------------------------------------


def _draw(surface: pygame.Surface, pg: Any, frame: Frame) -> None:
    """Draw the whole picture of ``frame`` on ``surface``."""
    if not isinstance(frame, Frame):
        raise TypeError(f"frame must be a Frame, got {type(frame).__name__}")
    width, height = surface.get_size()
    side_rect, trace_rect = panel_rects(width, height)
    font = _load_font(pg)
    _draw_side_view(surface.subsurface(side_rect), pg, font, frame)
    _draw_trace(surface.subsurface(trace_rect), pg, font, frame)


def render_rgb(frame: Frame, width: int = 720, height: int = 480) -> npt.NDArray[np.uint8]:
    """Render ``frame`` to an RGB image.

    Parameters
    ----------
    frame : Frame
        What to show.
    width, height : int, optional
        Picture size in pixels (each ``>= 32``).

    Returns
    -------
    numpy.ndarray
        A new ``(height, width, 3)`` ``uint8`` array, rows top to bottom.

    Raises
    ------
    gymnasium.error.DependencyNotInstalled
        If pygame is not installed.
    """
    width, height = _check_size(width, height)
    pg = _import_pygame()
    surface = pg.Surface((width, height))
    _draw(surface, pg, frame)
    return np.ascontiguousarray(
        np.transpose(np.array(pg.surfarray.pixels3d(surface)), axes=(1, 0, 2)), dtype=np.uint8
    )


class HumanWindow:
    """A pygame window showing frames at a fixed rate (Gymnasium's ``human`` render mode).

    The window opens on the first :meth:`show` and closes with :meth:`close`; showing again
    after closing opens a new window.

    Parameters
    ----------
    width, height : int, optional
        Window size in pixels (each ``>= 32``).
    fps : int, optional
        Frames per second :meth:`show` is limited to (``> 0``).

    Raises
    ------
    gymnasium.error.DependencyNotInstalled
        If pygame is not installed.
    """

    def __init__(self, width: int = 720, height: int = 480, fps: int = 30) -> None:
        self.width, self.height = _check_size(width, height)
        if isinstance(fps, bool) or not isinstance(fps, (int, np.integer)) or fps <= 0:
            raise ValueError(f"fps={fps!r} must be a positive int")
        self.fps = int(fps)
        self._pg: Any = _import_pygame()
        self._window: Any | None = None
        self._canvas: Any | None = None
        self._clock: Any | None = None

    @property
    def is_open(self) -> bool:
        """Whether the window is currently open."""
        return self._window is not None

    def _open(self) -> None:
        pg = self._pg
        pg.init()
        pg.display.init()
        pg.display.set_caption("subenv: dive planes")
        self._window = pg.display.set_mode((self.width, self.height))
        self._canvas = pg.Surface((self.width, self.height))
        self._clock = pg.time.Clock()

    def show(self, frame: Frame) -> None:
        """Draw ``frame`` in the window, pump window events and wait to keep to ``fps``.

        Parameters
        ----------
        frame : Frame
            What to show.
        """
        if self._window is None:
            self._open()
        assert self._window is not None and self._canvas is not None
        assert self._clock is not None
        pg = self._pg
        _draw(self._canvas, pg, frame)
        self._window.blit(self._canvas, (0, 0))
        pg.event.pump()
        self._clock.tick(self.fps)
        pg.display.flip()

    def close(self) -> None:
        """Close the window and shut pygame down; safe to call more than once."""
        if self._window is None:
            return
        self._window = self._canvas = self._clock = None
        self._pg.display.quit()
        self._pg.quit()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
