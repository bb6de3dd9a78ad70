"""The scenarios shipped with subenv, registered on import.

Speeds below, near and through critical are given relative to the episode's own critical speed
(Riedel 1993 eq. 3.9), so they keep their meaning for any vehicle, loading and plane allocation.
For DARPA SUBOFF at alpha = 0, u_cr = 1.8979 fps = 0.5785 m/s.
"""

from __future__ import annotations

import dataclasses
from typing import Final

from subenv.dynamics.free_surface import FreeSurface
from subenv.dynamics.waves import SeaState
from subenv.scenarios.registry import register_scenario
from subenv.scenarios.scenario import Scenario, SpeedRamp
from subenv.thesis import REFERENCE_LENGTH_M, THESIS_DESIGN_SPEED_MPS

__all__ = ["BASE_SCENARIOS", "HARD_SCENARIOS"]

_SMALL_PITCH = (-0.05, 0.05)  # rad, about +-3 deg
# The scenarios' depths, m/s speeds, times, loadings and disturbances are SUBOFF's (REFERENCE_LENGTH_M):
# on a vehicle of another length every episode is Froude-scaled (Scenario.reference_length_m).

NOMINAL = Scenario(
    name="Nominal",
    reference_length_m=REFERENCE_LENGTH_M,
    description="Design speed 5 fps (1.524 m/s), well above critical: the thesis controller works here.",
    speed_mps=(THESIS_DESIGN_SPEED_MPS, THESIS_DESIGN_SPEED_MPS),
    depth_command_m=(8.0, 15.0),
    initial_depth_offset_m=(-2.0, 2.0),
    initial_pitch_rad=_SMALL_PITCH,
    duration_s=200.0,
)
LOW_SPEED = Scenario(
    name="LowSpeed",
    reference_length_m=REFERENCE_LENGTH_M,
    description="Below the critical speed (0.3-0.8 u_cr): level flight is unstable and the planes reverse.",
    speed_ratio=(0.3, 0.8),
    depth_command_m=(8.0, 15.0),
    initial_depth_offset_m=(-2.0, 2.0),
    initial_pitch_rad=_SMALL_PITCH,
    duration_s=600.0,
)
NEAR_CRITICAL = Scenario(
    name="NearCritical",
    reference_length_m=REFERENCE_LENGTH_M,
    description="Within 15% of the critical speed, where the planes have almost no net effect on depth.",
    speed_ratio=(0.85, 1.15),
    depth_command_m=(8.0, 15.0),
    initial_depth_offset_m=(-2.0, 2.0),
    initial_pitch_rad=_SMALL_PITCH,
    duration_s=600.0,
)
SPEED_TRANSIENT = Scenario(
    name="SpeedTransient",
    reference_length_m=REFERENCE_LENGTH_M,
    description=(
        "Decelerates from 2-2.6 u_cr to 0.4-0.7 u_cr within the episode, through the critical speed, "
        "with a 0.3 N heave-force disturbance (below u_cr it reveals whether level flight is still stable)."
    ),
    speed_ratio=(2.0, 2.6),
    speed_ramp=SpeedRamp(final_speed_ratio=(0.4, 0.7), start_s=(30.0, 90.0), duration_s=(120.0, 240.0)),
    depth_command_m=(8.0, 15.0),
    initial_depth_offset_m=(-2.0, 2.0),
    initial_pitch_rad=_SMALL_PITCH,
    disturbance_std_N=0.3,
    duration_s=600.0,
)
PERISCOPE_DEPTH = Scenario(
    name="PeriscopeDepth",
    reference_length_m=REFERENCE_LENGTH_M,
    description=(
        "Ordered depth 1.0-1.2 m, near the surface; surface suction modelled as excess buoyancy "
        "(Riedel 1993 Ch. V.C); broaching ends the episode. Superseded by PeriscopeDepth-v1."
    ),
    speed_ratio=(0.7, 2.0),
    depth_command_m=(1.0, 1.2),
    initial_depth_offset_m=(-0.2, 0.6),
    initial_pitch_rad=(-0.02, 0.02),
    excess_buoyancy_fraction=(2e-4, 1e-3),
    duration_s=400.0,
)
BALLAST_OFFSET = Scenario(
    name="BallastOffset",
    reference_length_m=REFERENCE_LENGTH_M,
    description="Centre of gravity 0.5-3 mm fore or aft of buoyancy (x_GB != 0, Riedel 1993 Ch. IV).",
    speed_ratio=(0.6, 2.0),
    depth_command_m=(8.0, 15.0),
    initial_depth_offset_m=(-2.0, 2.0),
    initial_pitch_rad=_SMALL_PITCH,
    x_GB_m=(0.5e-3, 3e-3),
    x_GB_sign_random=True,
    duration_s=600.0,
)

BASE_SCENARIOS = (NOMINAL, LOW_SPEED, NEAR_CRITICAL, SPEED_TRANSIENT, PERISCOPE_DEPTH, BALLAST_OFFSET)

RANDOMIZED = Scenario(
    name="Randomized",
    reference_length_m=REFERENCE_LENGTH_M,
    description=(
        "Randomized: one of the scenarios above, with z_GB scaled by 0.8-1.25, C_D in 0-0.6, sensor "
        "noise and a heave-force disturbance."
    ),
    components=tuple(s.name for s in BASE_SCENARIOS),
    z_GB_scale=(0.8, 1.25),
    crossflow_drag=(0.0, 0.6),
    sensor_noise=True,
    disturbance_std_N=2.0,
)

MIXED = Scenario(
    name="Mixed",
    reference_length_m=REFERENCE_LENGTH_M,
    description=(
        "Mixed: one of the scenarios above, the low-speed, near-critical and speed-transient ones twice as "
        "often as the others, mildly randomized (z_GB scaled by 0.9-1.1, C_D in 0.2-0.4, sensor noise, a "
        "0.3 N heave-force disturbance): for training agents where the planes reverse."
    ),
    components=(
        "Nominal",
        "LowSpeed",
        "LowSpeed",
        "NearCritical",
        "NearCritical",
        "SpeedTransient",
        "SpeedTransient",
        "PeriscopeDepth",
        "BallastOffset",
    ),
    z_GB_scale=(0.9, 1.1),
    crossflow_drag=(0.2, 0.4),
    sensor_noise=True,
    disturbance_std_N=0.3,
)

PERISCOPE_DEPTH_V1 = PERISCOPE_DEPTH.replace(
    description=(
        "Ordered depth 1.0-1.2 m, near the surface, neutrally buoyant; the free surface pulls the hull up "
        "and pitches it (the Lagally force of the hull's sources alone, subenv.dynamics.free_surface's "
        "sources-only theory); broaching ends the episode. Superseded by PeriscopeDepth-v2."
    ),
    excess_buoyancy_fraction=(0.0, 0.0),
    free_surface=FreeSurface(theory="sources-only"),
    version=1,
)
PERISCOPE_DEPTH_V2 = PERISCOPE_DEPTH_V1.replace(
    description=(
        "Ordered depth 1.0-1.2 m, near the surface, neutrally buoyant; the free surface pulls the hull up "
        "and pitches it with a force that grows as u^2 and falls with depth, and changes the hull's "
        "heave and pitch derivatives (the consistent first-order slender-body theory under a rigid lid, "
        "subenv.dynamics.free_surface); broaching ends the episode."
    ),
    free_surface=FreeSurface(),
    version=2,
)
PERISCOPE_SEA: Final = SeaState(significant_height_m=0.06, peak_period_s=2.0)
"""PeriscopeDepthWaves's sea at SUBOFF's scale: H_s 6 cm, T_p 2 s; at 1:24 (SUBOFF as the model of a
102 m boat, Froude-scaled) H_s 1.4 m and T_p 9.8 s, sea state 4. At 1.1 m its waves push the hull
with 32 N and 42 N m rms (four times what the planes can answer at 0.6 m/s, but at periods of 1.5-2 s,
where the boat's inertia leaves millimetres of heave) and pull it up with 0.53 N on average."""
PERISCOPE_DEPTH_WAVES = PERISCOPE_DEPTH_V1.replace(
    name="PeriscopeDepthWaves",
    description=(
        "PeriscopeDepth-v1 in a head sea (JONSWAP, H_s 6 cm, T_p 2 s at SUBOFF's scale): the waves' "
        "oscillating heave force and pitch moment (at zero speed) and their mean suction "
        "(subenv.dynamics.waves), phases drawn per episode. Superseded by PeriscopeDepthWaves-v1."
    ),
    sea_state=dataclasses.replace(PERISCOPE_SEA, encounter_frequency=False),
    version=0,
)
PERISCOPE_DEPTH_WAVES_V1 = PERISCOPE_DEPTH_V2.replace(
    name="PeriscopeDepthWaves",
    description=(
        "PeriscopeDepth-v2 in a head sea (JONSWAP, H_s 6 cm, T_p 2 s at SUBOFF's scale): the waves' "
        "oscillating heave force and pitch moment at the boat's speed (forward-speed strip theory) and "
        "their mean suction (subenv.dynamics.waves), phases drawn per episode."
    ),
    sea_state=PERISCOPE_SEA,
    version=1,
)

for _scenario in (
    *BASE_SCENARIOS,
    RANDOMIZED,
    MIXED,
    PERISCOPE_DEPTH_V1,
    PERISCOPE_DEPTH_WAVES,
    PERISCOPE_DEPTH_V2,
    PERISCOPE_DEPTH_WAVES_V1,
):
    register_scenario(_scenario)

# --- the Hard track ------------------------------------------------------------------------------------
# Each an existing scenario made harder: what the best controllers do not all win, and what a
# full-information plan certifies can be won (the suite "hard", scored over those achievable episodes:
# subenv.evaluation.achievable). Their environment settings (the planes' rate limit, the pitch limit) are
# their ids' arguments, subenv.envs.registration.ID_ARGUMENTS, where gym.make and the harness read them.

HARD_RATE_TRANSIENT = SPEED_TRANSIENT.replace(
    name="HardRateTransient",
    description=(
        "SpeedTransient with rate-limited planes (its id's plane_rate_limit_radps): through u_cr the planes "
        "cannot follow a controller that does not plan for their rate."
    ),
)
HARD_BALLAST_LIMITS = BALLAST_OFFSET.replace(
    name="HardBallastLimits",
    description=(
        "BallastOffset with sensor noise, a 1 N heave-force disturbance, rate-limited planes and a tighter "
        "pitch limit (its id's plane_rate_limit_radps and max_pitch_rad)."
    ),
    sensor_noise=True,
    disturbance_std_N=1.0,
)
HARD_WAVES18 = PERISCOPE_DEPTH_WAVES.replace(
    name="HardWaves18",
    description=(
        "PeriscopeDepthWaves-v0 in a sea three times as high (JONSWAP, H_s 18 cm, T_p 2 s at SUBOFF's "
        "scale; at 1:24, H_s 4.3 m): the waves' forcing near the broaching depth. (v0's physics, the "
        "sources-only suction and the zero-speed wave force, as its episodes were certified.)"
    ),
    # The physics its stored certificates were computed in (PeriscopeDepthWaves-v0's): a version on the
    # slender-body theory and the encounter frequency is a new id, with new certificates.
    sea_state=dataclasses.replace(PERISCOPE_SEA, significant_height_m=0.18, encounter_frequency=False),
    version=0,
)
HARD_GUSTS = NEAR_CRITICAL.replace(
    name="HardGusts",
    description=(
        "NearCritical with sensor noise and a 6 N heave-force disturbance (30 s correlation): gusts the "
        "planes can barely answer where they have almost no net effect on depth."
    ),
    sensor_noise=True,
    disturbance_std_N=6.0,
)

HARD_SCENARIOS = (HARD_RATE_TRANSIENT, HARD_BALLAST_LIMITS, HARD_WAVES18, HARD_GUSTS)

for _scenario in HARD_SCENARIOS:
    register_scenario(_scenario)
