"""One page per registered id, written at build time (Gymnasium's ``docs/_scripts/gen_mds.py`` pattern).

Every id is :class:`subenv.envs.DivePlaneEnv` with a scenario, so a page is the environment's
docstring (its sections: Description, Action Space, Observation Space, Rewards, Starting State,
Episode End, Arguments, Vectorized environment, Version History) with what is the id's own put in:
its scenario's description and draw (from :class:`subenv.scenarios.Scenario`, each field described
by the class's own Attributes section), its registration (spaces, ``max_episode_steps``), the
Version History entries that name it, and an animation of one episode rendered with
``render_mode="rgb_array"`` under the ``reversal_aware`` baseline. An id registered tomorrow gets
its page from the same code.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import subenv
from subenv.envs import DivePlaneEnv
from subenv.scenarios import Scenario, get_scenario

SECTIONS = (
    "Description",
    "Action Space",
    "Observation Space",
    "Rewards",
    "Starting State",
    "Episode End",
    "Arguments",
    "Vectorized environment",
    "Version History",
)
"""The sections of the environment's docstring, in order (STYLE.md: Gymnasium's, and the vector env's)."""

ANIMATION_STEPS = 240
"""Control periods shown (2 minutes at the default 0.5 s)."""
ANIMATION_EVERY = 4
"""One frame every this many steps: 60 frames, played at 10 per second (a 4x time lapse at 0.5 s)."""
ANIMATION_SIZE = (540, 360)
"""Width and height of the animation [px]: the environment's 720 x 480 frame, scaled down."""
ANIMATION_SEED = 0
ANIMATION_CONTROLLER = "reversal_aware"


def page_name(env_id: str) -> str:
    """The page's file name without suffix: the id without its namespace (``LowSpeed-v0``)."""
    return env_id.split("/", 1)[-1]


def docstring_sections(doc: str) -> dict[str, str]:
    """The environment docstring's ``## Name`` sections, name -> body (dedented, stripped)."""
    text = inspect.cleandoc(doc)
    parts = re.split(r"^## (.+)$", text, flags=re.MULTILINE)
    return {name.strip(): body.strip() for name, body in zip(parts[1::2], parts[2::2], strict=True)}


def to_myst(text: str) -> str:
    """A docstring's Markdown as MyST: Sphinx's ``:role:`target``` cross-references become
    ``{role}`target```; the rest (``code``, tables, fenced blocks) is Markdown already."""
    return re.sub(r"(?<![\w`]):(\w+):`", r"{\1}`", text)


def version_history(section: str, scenario: Scenario) -> str:
    """The Version History entries that concern ``scenario``: those opening with a version alone
    (``- v0: ...``, every id's) and those opening with its name (````PeriscopeDepth-v1```` ...);
    the whole section if none is found (a format this function does not know)."""
    items = re.split(r"\n(?=- )", section.strip())
    own = re.compile(rf"^- ``{re.escape(scenario.name)}-v\d+``")
    every = re.compile(r"^- v\d+\b")
    kept = [item for item in items if own.match(item) or every.match(item)]
    return "\n".join(kept) if kept else section


def attribute_descriptions(cls: type) -> dict[str, str]:
    """A numpydoc Attributes section as name -> one-line description (names listed together share it)."""
    doc = inspect.cleandoc(cls.__doc__ or "")
    section = doc.split("Attributes\n----------\n", 1)[-1]
    described: dict[str, str] = {}
    for names, body in re.findall(
        r"^(\w[\w, ]*) : [^\n]*\n((?:    [^\n]*\n?)+)", section, flags=re.MULTILINE
    ):
        line = " ".join(part.strip() for part in body.splitlines())
        for name in names.split(","):
            described[name.strip()] = line
    return described


def _value(value: Any) -> str:
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, int | float) for v in value):
        low, high = value
        return f"{low:g}" if low == high else f"{low:g} to {high:g}"
    if isinstance(value, tuple):
        return ", ".join(str(v) for v in value)
    if dataclasses.is_dataclass(value):
        fields = ", ".join(f"{f.name}={getattr(value, f.name)!r}" for f in dataclasses.fields(value))
        return f"{type(value).__name__}({fields})"
    return f"{value:g}" if isinstance(value, float) else str(value)


MIXTURE_FIELDS = ("z_GB_scale", "crossflow_drag", "sensor_noise", "disturbance_std_N", "reference_length_m")
"""What a mixture applies on top of its component's draw (:class:`~subenv.scenarios.Scenario`'s docstring);
its other fields are its components'."""


def scenario_table(scenario: Scenario) -> str:
    """The scenario's draw: every field that differs from :class:`Scenario`'s default (a mixture's:
    those of :data:`MIXTURE_FIELDS`), described."""
    described = attribute_descriptions(Scenario)
    rows = ["| field | value | meaning |", "|---|---|---|"]
    for field in dataclasses.fields(Scenario):
        value = getattr(scenario, field.name)
        if field.name in ("name", "description", "components") or value == field.default:
            continue
        if scenario.components and field.name not in MIXTURE_FIELDS:
            continue
        meaning = described.get(field.name, "").replace("|", "\\|")
        rows.append(f"| `{field.name}` | {_value(value).replace('|', chr(92) + '|')} | {to_myst(meaning)} |")
    return "\n".join(rows)


def _components(scenario: Scenario) -> str:
    if not scenario.components:
        return ""
    ids = []
    for name in dict.fromkeys(scenario.components):
        component = get_scenario(name)
        share = scenario.components.count(name) / len(scenario.components)
        ids.append(f"[`{component.env_id}`]({page_name(component.env_id)}.md) ({share:.0%})")
    return "Each episode is drawn from one of " + ", ".join(ids) + ", then randomised as below.\n\n"


def _gif_frame(frame: Any) -> Any:
    """A rendered frame at :data:`ANIMATION_SIZE` in 64 colours (Pillow's fast octree: a third of median
    cut's time, the default, at no difference we could see on these flat-coloured frames). Scaled down
    bilinearly (Pillow's filters widen with the scale, so this one smooths too): no difference we could
    see from Lanczos at this scale, in half its time."""
    from PIL import Image

    return frame.resize(ANIMATION_SIZE, Image.Resampling.BILINEAR).quantize(
        colors=64, method=Image.Quantize.FASTOCTREE
    )


def render_animation(env_id: str, path: Path) -> None:
    """One episode (seed :data:`ANIMATION_SEED`) under :data:`ANIMATION_CONTROLLER`, as an animated GIF."""
    from PIL import Image

    from subenv.evaluation import make_controller

    controller = make_controller(ANIMATION_CONTROLLER)
    env = gym.make(env_id, render_mode="rgb_array", control=controller.control, alpha=controller.alpha)
    base: Any = env.unwrapped
    obs, info = env.reset(seed=ANIMATION_SEED)
    controller.reset(info, base.base_vehicle)
    frames = []
    for step in range(ANIMATION_STEPS + 1):
        if step % ANIMATION_EVERY == 0:
            frame = Image.fromarray(np.asarray(env.render()))
            frames.append(_gif_frame(frame))
        obs, _, terminated, truncated, _ = env.step(controller.act(obs))
        if terminated or truncated:
            frames.append(_gif_frame(Image.fromarray(np.asarray(env.render()))))
            break
    env.close()
    path.parent.mkdir(parents=True, exist_ok=True)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=100, loop=0, optimize=True)


def env_page(env_id: str, animation: str) -> str:
    """The page of ``env_id`` (MyST), showing the animation file ``animation`` (relative to the page)."""
    spec = gym.spec(env_id)
    env = gym.make(env_id)
    base: Any = env.unwrapped
    scenario = base.scenario
    action_space, observation_space = env.action_space, env.observation_space
    env.close()
    doc = docstring_sections(DivePlaneEnv.__doc__ or "")
    missing = [name for name in SECTIONS if name not in doc]
    if missing:
        raise ValueError(f"DivePlaneEnv's docstring has no section {missing}: the env pages need {SECTIONS}")
    sections = {name: to_myst(body) for name, body in doc.items()}
    sections["Version History"] = version_history(sections["Version History"], scenario)
    kwargs = ", ".join(f"{k}={v!r}" for k, v in spec.kwargs.items())
    summary = [
        "|   |   |",
        "|---|---|",
        f'| Action Space | `{action_space}` (`control="dual"`) |',
        f"| Observation Space | `Box(shape={observation_space.shape}, {observation_space.dtype})`, "
        "the bounds in [its table](#observation-space) |",
        f'| import | `gym.make("{env_id}")` after `import subenv` |',
        f"| scenario | `{kwargs}` |",
        f"| `max_episode_steps` | {spec.max_episode_steps} (at `dt` = {base.dt:g} s) |",
        f"| vector entry point | `{spec.vector_entry_point}` |",
    ]
    starting = (
        f"This id's scenario, `{scenario.key}`: {scenario.description}\n\n"
        + _components(scenario)
        + scenario_table(scenario)
    )
    body = [
        f"# {env_id}",
        "",
        f"```{{image}} {animation}",
        f":alt: an episode of {env_id} under the {ANIMATION_CONTROLLER} baseline",
        ":class: env-animation",
        "```",
        "",
        f"*One episode (seed {ANIMATION_SEED}) under the `{ANIMATION_CONTROLLER}` baseline, "
        f'{ANIMATION_STEPS * base.dt:g} s at {ANIMATION_EVERY}x speed, `render_mode="rgb_array"`.*',
        "",
        f"**{scenario.description}**",
        "",
        *summary,
        "",
    ]
    for name in SECTIONS:
        body += [f"## {name}", ""]
        if name == "Starting State":
            body += [starting, "", "In every scenario:", ""]
        body += [sections[name], ""]
    return "\n".join(body)


def index_page(env_ids: list[str]) -> str:
    """The environments' index: a table of every id and its scenario's description."""
    rows = ["| id | scenario |", "|---|---|"]
    for env_id in env_ids:
        scenario = get_scenario(gym.spec(env_id).kwargs["scenario"])
        rows.append(f"| [`{env_id}`]({page_name(env_id)}.md) | {scenario.description} |")
    return "\n".join(
        [
            "# Environments",
            "",
            "Every id is {class}`subenv.envs.DivePlaneEnv` with a scenario: the same physics, action and",
            "observation, and the episodes its scenario draws. `import subenv` registers them;",
            "`gym.make_vec(id, num_envs=N)` builds the native vector environment",
            "({class}`subenv.envs.DivePlaneVectorEnv`).",
            "",
            *rows,
            "",
            "```{toctree}",
            ":hidden:",
            "",
            *(page_name(env_id) for env_id in env_ids),
            "```",
            "",
        ]
    )


def write_pages(folder: Path) -> list[Path]:
    """Write the index, a page per id and its animation into ``folder``; returns the pages."""
    folder.mkdir(parents=True, exist_ok=True)
    ids = subenv.env_ids()
    pages = [folder / "index.md"]
    pages[0].write_text(index_page(ids), "utf-8")
    for env_id in ids:
        name = page_name(env_id)
        render_animation(env_id, folder / f"{name}.gif")
        page = folder / f"{name}.md"
        page.write_text(env_page(env_id, f"{name}.gif"), "utf-8")
        pages.append(page)
    return pages
