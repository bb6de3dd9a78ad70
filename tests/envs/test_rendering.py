"""Tests of subenv.envs.rendering: pixels, geometry signs, determinism and the human window."""

from __future__ import annotations

import dataclasses
import math
import os
import sys

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import numpy as np
import numpy.typing as npt
import pytest

pytest.importorskip("pygame", reason="the 'render' extra is not installed")

from gymnasium.error import DependencyNotInstalled

from subenv.envs import rendering
from subenv.envs.rendering import (
    COMMAND_RGB,
    DEPTH_RGB,
    HULL_RGB,
    PLANE_RGB,
    SURFACE_RGB,
    Frame,
    HumanWindow,
    panel_rects,
    render_rgb,
)
from subenv.vehicles import load_vehicle

Image = npt.NDArray[np.uint8]


@pytest.fixture(scope="module")
def frame() -> Frame:
    """A deep, level frame with a 20 s history converging from 10 m towards a 15 m command."""
    v = load_vehicle("suboff")
    t = np.linspace(0.0, 20.0, 201)
    return Frame(
        hull_x_m=tuple(v.hull.x_m),
        hull_breadth_m=tuple(v.hull.breadth_m),
        length_m=v.length_m,
        pitch_rad=0.0,
        depth_m=14.0,
        depth_command_m=15.0,
        stern_plane_rad=0.1,
        bow_plane_rad=-0.1,
        speed_mps=2.5,
        critical_speed_mps=0.8,
        time_s=20.0,
        times_s=tuple(t),
        depths_m=tuple(10.0 + 4.0 * (1.0 - np.exp(-t / 5.0))),
        commands_m=tuple(np.full_like(t, 15.0)),
    )


def _mask(img: Image, colour: tuple[int, int, int]) -> npt.NDArray[np.bool_]:
    return np.all(img == np.asarray(colour, dtype=np.uint8), axis=-1)


def _crop(img: Image, rect: tuple[int, int, int, int]) -> Image:
    left, top, w, h = rect
    return img[top : top + h, left : left + w]


def _centroid_row(mask: npt.NDArray[np.bool_]) -> float:
    rows, _ = np.nonzero(mask)
    assert rows.size > 0, "no pixels of the colour"
    return float(rows.mean())


# --- output format and determinism -------------------------------------------------------


@pytest.mark.parametrize("size", [(720, 480), (400, 300), (960, 360)])
def test_shape_and_dtype(frame: Frame, size: tuple[int, int]) -> None:
    width, height = size
    img = render_rgb(frame, width, height)
    assert isinstance(img, np.ndarray)
    assert img.shape == (height, width, 3)
    assert img.dtype == np.uint8
    assert img.flags.c_contiguous
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 5  # an actual picture


def test_default_size(frame: Frame) -> None:
    assert render_rgb(frame).shape == (480, 720, 3)


def test_same_frame_renders_identically(frame: Frame) -> None:
    a = render_rgb(frame)
    b = render_rgb(frame)
    assert a is not b
    np.testing.assert_array_equal(a, b)
    # An equal frame built anew renders the same, too.
    np.testing.assert_array_equal(render_rgb(dataclasses.replace(frame)), a)


def test_returned_array_is_independent(frame: Frame) -> None:
    a = render_rgb(frame)
    expected = a.copy()
    a[:] = 0
    np.testing.assert_array_equal(render_rgb(frame), expected)


def test_panel_layout() -> None:
    side, trace = panel_rects(720, 480)
    assert side[:2] == (0, 0) and side[2] == 720 and trace[2] == 720
    assert trace[1] == side[3] and side[3] + trace[3] == 480  # stacked, side view on top
    side, trace = panel_rects(960, 360)
    assert side[3] == trace[3] == 360 and trace[0] == side[2]  # side by side
    assert side[2] + trace[2] == 960


# --- side view geometry ------------------------------------------------------------------


def test_pitch_changes_output(frame: Frame) -> None:
    a = render_rgb(frame)
    b = render_rgb(dataclasses.replace(frame, pitch_rad=0.1))
    assert not np.array_equal(a, b)


def test_nose_up_raises_nose_and_lowers_tail(frame: Frame) -> None:
    side, _ = panel_rects(720, 480)
    mid = side[2] // 2

    def rows(pitch: float) -> tuple[float, float]:
        hull = _mask(_crop(render_rgb(dataclasses.replace(frame, pitch_rad=pitch)), side), HULL_RGB)
        return _centroid_row(hull[:, mid:]), _centroid_row(hull[:, :mid])

    nose_up, tail_up = rows(0.2)
    nose_level, tail_level = rows(0.0)
    nose_down, tail_down = rows(-0.2)
    # Screen rows grow downward: a nose-up pitch puts the nose (right half) higher, i.e. at
    # smaller rows, and the tail lower.
    assert nose_up < nose_level - 5 < nose_down - 10
    assert tail_up > tail_level + 5 > tail_down + 10


def test_level_hull_is_symmetric_about_its_axis(frame: Frame) -> None:
    side, _ = panel_rects(720, 480)
    hull = _mask(_crop(render_rgb(frame), side), HULL_RGB)
    rows, cols = np.nonzero(hull)
    # Nose on the right: the hull's horizontal extent is about the scaled hull length, and the
    # upper and lower halves have the same number of rows.
    assert cols.max() > side[2] // 2 > cols.min()
    height = rows.max() - rows.min()
    length = cols.max() - cols.min()
    v = load_vehicle("suboff")
    assert length / height == pytest.approx(v.length_m / max(v.hull.breadth_m), rel=0.15)


def test_planes_at_tail_and_nose_and_rotate_with_their_angle(frame: Frame) -> None:
    side, _ = panel_rects(720, 480)
    mid = side[2] // 2
    base = _crop(render_rgb(frame), side)
    planes = _mask(base, PLANE_RGB)
    assert planes[:, :mid].any() and planes[:, mid:].any()

    moved = _crop(render_rgb(dataclasses.replace(frame, stern_plane_rad=-0.3)), side)
    changed = (_mask(moved, PLANE_RGB) != planes).nonzero()[1]
    assert changed.size > 0
    assert changed.max() < mid  # only the stern (left) planes moved

    # A positive stern-plane angle turns the leading (right) edge up.
    def slope(img: Image) -> float:
        rows, cols = np.nonzero(_mask(img, PLANE_RGB)[:, :mid])
        return float(np.polyfit(cols, rows, 1)[0])

    up = _crop(render_rgb(dataclasses.replace(frame, stern_plane_rad=0.35)), side)
    down = _crop(render_rgb(dataclasses.replace(frame, stern_plane_rad=-0.35)), side)
    assert slope(up) < 0 < slope(down)  # rows decrease to the right when the edge is up


def test_water_surface_drawn_only_near_the_surface(frame: Frame) -> None:
    side, _ = panel_rects(720, 480)

    def surface_rows(depth: float) -> npt.NDArray[np.intp]:
        img = _crop(render_rgb(dataclasses.replace(frame, depth_m=depth)), side)
        return np.nonzero(_mask(img, SURFACE_RGB).sum(axis=1) > 0.9 * side[2])[0]

    shallow = surface_rows(1.0)
    assert shallow.size > 0
    hull_rows = np.nonzero(_mask(_crop(render_rgb(dataclasses.replace(frame, depth_m=1.0)), side), HULL_RGB))[
        0
    ]
    assert shallow.max() < hull_rows.min()  # the surface is above the hull
    assert surface_rows(30.0).size == 0


# --- depth trace -------------------------------------------------------------------------


def test_commanded_depth_line_in_trace_panel(frame: Frame) -> None:
    _, trace = panel_rects(720, 480)
    panel = _crop(render_rgb(frame), trace)
    command = _mask(panel, COMMAND_RGB)
    depth = _mask(panel, DEPTH_RGB)
    # A constant command over the whole history: a dashed line across most of the axes, not
    # just the legend sample.
    assert np.count_nonzero(command.any(axis=0)) > 0.5 * trace[2]
    # Depth increases downward: the 15 m command is below the 10-14 m trace, and the trace,
    # which deepens with time, is lower on the right than on the left.
    command_row = float(np.median(np.nonzero(command)[0]))
    depth_rows, depth_cols = np.nonzero(depth[trace[3] // 6 :])  # below the legend
    assert command_row > depth_rows.max() + trace[3] // 6
    left = depth_rows[depth_cols < np.percentile(depth_cols, 20)].mean()
    right = depth_rows[depth_cols > np.percentile(depth_cols, 80)].mean()
    assert right > left


def test_command_line_moves_with_command(frame: Frame) -> None:
    _, trace = panel_rects(720, 480)

    def command_row(value: float) -> float:
        f = dataclasses.replace(frame, depth_command_m=value, commands_m=(value,) * len(frame.times_s))
        mask = _mask(_crop(render_rgb(f), trace), COMMAND_RGB)
        counts = mask.sum(axis=1)
        return float(np.argmax(counts))  # the row of the long dashed line

    assert command_row(16.0) > command_row(12.0)


def test_empty_history(frame: Frame) -> None:
    empty = dataclasses.replace(frame, times_s=(), depths_m=(), commands_m=())
    img = render_rgb(empty)
    assert img.shape == (480, 720, 3) and img.dtype == np.uint8
    _, trace = panel_rects(720, 480)
    panel = _crop(img, trace)
    # Only the legend samples carry the line colours.
    assert np.count_nonzero(_mask(panel, COMMAND_RGB).any(axis=0)) < 0.1 * trace[2]
    assert np.count_nonzero(_mask(panel, DEPTH_RGB).any(axis=0)) < 0.1 * trace[2]
    # The side view is unaffected by the history.
    side, _ = panel_rects(720, 480)
    np.testing.assert_array_equal(_crop(img, side), _crop(render_rgb(frame), side))


def test_single_point_and_non_finite_history(frame: Frame) -> None:
    one = dataclasses.replace(frame, times_s=(0.0,), depths_m=(3.0,), commands_m=(4.0,))
    assert render_rgb(one).shape == (480, 720, 3)
    gappy = dataclasses.replace(
        frame,
        depths_m=(math.nan, *frame.depths_m[1:]),
        commands_m=(*frame.commands_m[:50], math.nan, *frame.commands_m[51:]),
        critical_speed_mps=math.nan,
        depth_command_m=math.nan,
    )
    assert render_rgb(gappy).shape == (480, 720, 3)


# --- Frame ---------------------------------------------------------------------------------


def test_frame_converts_sequences_to_float_tuples(frame: Frame) -> None:
    f = dataclasses.replace(
        frame,
        hull_x_m=np.asarray(frame.hull_x_m),
        times_s=list(frame.times_s),
        depths_m=np.asarray(frame.depths_m),
        commands_m=np.asarray(frame.commands_m),
        depth_m=np.float32(14.0),
    )
    assert isinstance(f.hull_x_m, tuple) and isinstance(f.times_s, tuple)
    assert all(type(v) is float for v in f.depths_m)
    assert type(f.depth_m) is float
    assert f == frame
    hash(f)


@pytest.mark.parametrize(
    "changes",
    [
        {"times_s": (0.0, 1.0)},
        {"hull_breadth_m": (0.1, 0.2)},
        {"hull_x_m": (1.0,), "hull_breadth_m": (0.1,)},
        {"length_m": 0.0},
        {"pitch_rad": math.nan},
        {"depth_m": math.inf},
    ],
)
def test_frame_rejects_inconsistent_input(frame: Frame, changes: dict[str, object]) -> None:
    with pytest.raises(ValueError):
        dataclasses.replace(frame, **changes)


# --- text, dependencies, sizes -----------------------------------------------------------


def test_text_changes_with_the_numbers(frame: Frame) -> None:
    side, _ = panel_rects(720, 480)
    # Speed is drawn only in the header text.
    a = render_rgb(frame)
    b = render_rgb(dataclasses.replace(frame, speed_mps=3.5))
    diff_rows = np.nonzero(np.any(a != b, axis=(1, 2)))[0]
    assert diff_rows.size > 0 and diff_rows.max() < side[3] // 4


def test_renders_without_fonts(frame: Frame, monkeypatch: pytest.MonkeyPatch) -> None:
    with_text = render_rgb(frame)
    monkeypatch.setattr(rendering, "_load_font", lambda pg: None)
    without_text = render_rgb(frame)
    assert without_text.shape == with_text.shape
    assert not np.array_equal(without_text, with_text)
    assert _mask(without_text, HULL_RGB).any() and _mask(without_text, COMMAND_RGB).any()


def test_missing_pygame_raises_dependency_not_installed(
    frame: Frame, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` fail
    message = r'the .render. extra is needed for rendering: pip install "subenv\[render\]"'
    with pytest.raises(DependencyNotInstalled, match=message) as error:
        render_rgb(frame)
    assert "./dev installs every extra" in str(error.value) and "\n" not in str(error.value)
    with pytest.raises(DependencyNotInstalled):
        HumanWindow()


@pytest.mark.parametrize("size", [(10, 480), (720, 0), (720.0, 480)])
def test_bad_sizes_rejected(frame: Frame, size: tuple[int, int]) -> None:
    with pytest.raises((ValueError, TypeError)):
        render_rgb(frame, *size)


# --- human window ------------------------------------------------------------------------


def test_human_window_shows_and_closes(frame: Frame) -> None:
    import pygame

    window = HumanWindow(320, 240, fps=1000)
    assert not window.is_open
    for k in range(3):
        window.show(dataclasses.replace(frame, time_s=frame.time_s + k, pitch_rad=0.05 * k))
        assert window.is_open
        assert pygame.display.get_surface().get_size() == (320, 240)
    window.close()
    assert not window.is_open
    assert not pygame.display.get_init()
    window.close()  # idempotent

    # Rendering to arrays still works after the window shut pygame down.
    assert render_rgb(frame).shape == (480, 720, 3)


def test_human_window_context_manager_and_reopen(frame: Frame) -> None:
    with HumanWindow(fps=1000) as window:
        window.show(frame)
        window.close()
        window.show(frame)  # opens a new window
        assert window.is_open
    assert not window.is_open


def test_human_window_rejects_bad_fps() -> None:
    with pytest.raises(ValueError):
        HumanWindow(fps=0)
