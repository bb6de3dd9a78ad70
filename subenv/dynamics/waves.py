"""A seaway at periscope depth: a JONSWAP sea's heave force and pitch moment on the hull, written once.

The sea is long-crested and meets the boat head on: a sum of N regular waves

    eta(X, t) = sum_i A_i cos(K_i X + omega_i t + phi_i),   K_i = omega_i^2 / g (deep water),

travelling towards -X while the boat advances along +X (X is the distance it has travelled). The
amplitudes follow the JONSWAP spectrum (Hasselmann et al. 1973, "Measurements of wind-wave growth
and swell decay during the Joint North Sea Wave Project", Dtsch. Hydrogr. Z. A8(12); in the
significant-height form of DNV-RP-C205 (2010) section 3.5.5):

    S(omega) = (1 - 0.287 ln gamma) (5/16) H_s^2 omega_p^4 omega^-5 exp(-5/4 (omega_p / omega)^4)
               gamma^exp(-(omega - omega_p)^2 / (2 sigma^2 omega_p^2)),
    sigma = 0.07 (omega <= omega_p), 0.09 (omega > omega_p),

one wave per frequency bin of width d omega, A_i = sqrt(2 S(omega_i) d omega), with a random phase
and a random frequency within its bin (drawn at the reset from the episode's generator: a seed gives
one sea). The elevation's variance is sum A_i^2 / 2 = int S d omega over the band.

Forces (valid for a slender hull of revolution deep enough that it does not disturb the surface,
h > b, and waves longer than the hull's diameter, K b << 1):

- *First order, oscillating.* Each section feels the incident wave's pressure gradient (Froude-Krylov)
  and its diffraction, (rho S(x) + a_33(x)) times the water's vertical acceleration there (G. I.
  Taylor 1928, "The forces on a body placed in a curved or converging stream of fluid", Proc. R. Soc.
  A 120; Newman 1977, *Marine Hydrodynamics*, ch. 6, the long-wave force on a small body), a_33 =
  rho S for a circular section. Integrated over the hull at its mean position (the consistent
  first-order theory: pitch enters at second order), each wave gives

      F_up,i = -A_i omega_i^2 e^(-K_i Z) Re[e^(i psi_i) int 2 rho S(x) e^(i K_i x) dx],
      psi_i = K_i X + omega_i t + phi_i,

  and the moment with one more factor x. Zero mean.
- *Forward speed.* At the boat's speed u the waves meet it at the encounter frequency
  omega_e = omega + K u, and the diffraction part, in the boat's frame the rate of change of the
  sections' added-mass momentum following the stream, (d/dt - u d/dx)(a_33 w) (forward-speed strip
  theory, Salvesen, Tuck and Faltinsen 1970, "Ship motions and sea loads", Trans. SNAME 78; the
  steady form of the same term is the free surface's U int a_33 w dx, :mod:`subenv.dynamics.free_surface`),
  integrates over the hull to

      F_a33 = i omega_e int a_33 w dx,   M_a33 = i omega_e int x a_33 w dx + u int a_33 w dx,

  w the incident wave's vertical velocity at the axis: the added-mass half of the force above grows by
  omega_e / omega = 1 + omega u / g, and the moment gains u int a_33 w dx. The Froude-Krylov half is the
  water's own acceleration and does not change. Each wave's record holds the zero-speed coefficients and
  these per unit speed; :func:`wave_force_point` adds them at the boat's speed (zero for a sea with
  :attr:`SeaState.encounter_frequency` False, the zero-speed form of ``PeriscopeDepthWaves-v0``).
- *Second order, the mean suction.* A body in the orbital flow of a wave is pulled to where the
  flow is faster, upwards: per unit length (rho S + a_33) d/dz (|v|^2 / 2), with |v|^2 =
  A^2 omega^2 e^(-2 K h) for a deep-water wave (Taylor 1928), so

      F_mean,i = K_i A_i^2 omega_i^2 e^(-2 K_i Z) int 2 rho S dx      (up),

  summed over the waves. Lee and Newman (1971, "The vertical mean force and moment of submerged
  bodies under waves", J. Ship Res. 15) show that for a deeply submerged slender body the mean force
  depends on the distribution of sectional area and added mass, as here; their result for a body free
  to respond differs from this restrained-body value by a factor that depends on the body's motion,
  which is not given in closed form: :attr:`SeaState.mean_suction_factor` (1: restrained body). The
  mean force is the zero-speed one at every speed: its forward-speed correction is of the relative
  order of the first-order one, omega u / g (19% at PeriscopeDepthWaves' peak frequency and 0.6 m/s;
  :func:`encounter_factor`), and was not found in closed form for a slender body.

:func:`wave_force_point` evaluates both for one state; the block integrator
(:func:`subenv.dynamics.integrate.control_period_lanes`) calls it at every stage, so the force varies
within a control period. The analysis takes the mean suction as a function of depth
(:meth:`SeaState.mean_suction`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from subenv import _validation as check
from subenv._typing import ArrayLike, FloatArray
from subenv.dynamics._jit import Static, inline_kernel

__all__ = [
    "MAX_WAVES",
    "WAVE_FIELDS",
    "SeaState",
    "encounter_factor",
    "hull_wave_integrals",
    "wave_force_point",
    "wave_term",
]

MAX_WAVES: Final = 24
"""Regular waves a sea is made of, at most (an episode's record holds this many)."""
WAVE_FIELDS: Final = 13
"""Numbers per wave in an episode's record: K [1/m], omega [rad/s], phase [rad], the first-order force's
cos and sin coefficients at zero speed [N], the moment's [N m], the mean force [N] and moment [N m], and the
first-order force's and moment's cos and sin coefficients per unit forward speed [N s/m, N s]."""
(
    _K,
    _OMEGA,
    _PHASE,
    _F_COS,
    _F_SIN,
    _M_COS,
    _M_SIN,
    _F_MEAN,
    _M_MEAN,
    _F_SPEED_COS,
    _F_SPEED_SIN,
    _M_SPEED_COS,
    _M_SPEED_SIN,
) = range(WAVE_FIELDS)

_SIGMA_LOW, _SIGMA_HIGH = 0.07, 0.09  # JONSWAP peak widths below and above omega_p (Hasselmann et al. 1973)
_PM_NORMALISATION = 0.287  # A_gamma = 1 - 0.287 ln(gamma), DNV-RP-C205 eq. 3.5.5.3


@dataclass(frozen=True)
class SeaState:
    """A long-crested JONSWAP sea from ahead (see the module's docstring).

    Attributes
    ----------
    significant_height_m : float
        H_s = 4 sqrt(m_0) [m].
    peak_period_s : float
        T_p = 2 pi / omega_p [s].
    peak_enhancement : float
        gamma, in [1, 7] (DNV-RP-C205's range; 1 is Pierson-Moskowitz, 3.3 the JONSWAP mean).
    waves : int
        Regular waves the sea is made of (1 .. :data:`MAX_WAVES`).
    band : tuple of float
        The frequency band they cover, as multiples of omega_p.
    mean_suction_factor : float
        Multiplies the second-order mean suction (1: a restrained body; see the module docstring).
    encounter_frequency : bool
        The first-order force at the boat's speed (forward-speed strip theory, module docstring); False:
        at zero speed, the form of ``PeriscopeDepthWaves-v0``.
    """

    significant_height_m: float
    peak_period_s: float
    peak_enhancement: float = 3.3
    waves: int = 24
    band: tuple[float, float] = (0.6, 3.0)
    mean_suction_factor: float = 1.0
    encounter_frequency: bool = True

    def __post_init__(self) -> None:
        check.positive("significant_height_m", self.significant_height_m, upper=100.0)
        check.positive("peak_period_s", self.peak_period_s, upper=100.0)
        check.number("peak_enhancement", self.peak_enhancement, 1.0, 7.0)
        check.integer("waves", self.waves, 1, MAX_WAVES)
        low, high = check.interval("band", self.band, 0.0)
        if not 0.0 < low < 1.0 < high:
            raise ValueError(
                f"band={self.band!r} is invalid: must be (low, high) with 0 < low < 1 < high "
                "(multiples of the peak frequency)"
            )
        check.number("mean_suction_factor", self.mean_suction_factor, 0.0, 10.0)
        check.require(
            "encounter_frequency",
            self.encounter_frequency,
            isinstance(self.encounter_frequency, bool),
            "True or False",
        )

    @property
    def peak_frequency_radps(self) -> float:
        """omega_p [rad/s]."""
        return 2.0 * math.pi / self.peak_period_s

    def spectrum(self, omega_radps: ArrayLike) -> FloatArray:
        """S(omega) [m^2 s / rad] (DNV-RP-C205 eq. 3.5.5.1)."""
        w = np.asarray(omega_radps, dtype=float)
        wp, hs, gamma = self.peak_frequency_radps, self.significant_height_m, self.peak_enhancement
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            pm = 5.0 / 16.0 * hs * hs * wp**4 * w**-5.0 * np.exp(-1.25 * (wp / w) ** 4)
            sigma = np.where(w <= wp, _SIGMA_LOW, _SIGMA_HIGH)
            peak = gamma ** np.exp(-((w - wp) ** 2) / (2.0 * sigma * sigma * wp * wp))
            s = (1.0 - _PM_NORMALISATION * math.log(gamma)) * pm * peak
        return np.where(w > 0.0, s, 0.0)

    @property
    def bins(self) -> tuple[FloatArray, float]:
        """The bins' lower edges [rad/s] and width [rad/s]."""
        low, high = (f * self.peak_frequency_radps for f in self.band)
        width = (high - low) / self.waves
        return np.asarray(low + width * np.arange(self.waves), dtype=np.float64), width

    def frequencies(self, jitter: ArrayLike) -> FloatArray:
        """The waves' frequencies [rad/s], one per bin at ``jitter`` (in [0, 1)) across it."""
        edges, width = self.bins
        return edges + width * np.asarray(jitter, dtype=float)

    def amplitudes(self, omega_radps: ArrayLike) -> FloatArray:
        """A_i = sqrt(2 S(omega_i) d omega) [m]."""
        return np.sqrt(2.0 * self.spectrum(omega_radps) * self.bins[1])

    def band_variance_m2(self) -> float:
        """Int S d omega over the band [m^2] (adaptive quadrature): what the waves' variance
        sum A_i^2 / 2 approximates; H_s^2 / 16 over all frequencies."""
        from scipy.integrate import quad

        low, high = (f * self.peak_frequency_radps for f in self.band)
        return float(
            quad(lambda w: float(self.spectrum(w)), low, high, limit=200, points=[self.peak_frequency_radps])[
                0
            ]
        )

    def components(
        self,
        jitter: ArrayLike,
        phases_rad: ArrayLike,
        hull_x_m: ArrayLike,
        hull_breadth_m: ArrayLike,
        density_kg_m3: float,
        gravity_m_s2: float,
    ) -> FloatArray:
        """The waves of one sea as an episode's record holds them: shape (:data:`WAVE_FIELDS`,
        :data:`MAX_WAVES`), the unused columns zero (:func:`wave_force_point` reads the first
        :attr:`waves`)."""
        omega = self.frequencies(jitter)
        amplitude = self.amplitudes(omega)
        k = omega * omega / gravity_m_s2
        heave, pitch, mean_heave, mean_pitch = hull_wave_integrals(k, hull_x_m, hull_breadth_m, density_kg_m3)
        scale = -amplitude * omega * omega
        mean = self.mean_suction_factor * k * amplitude * amplitude * omega * omega
        out = np.zeros((WAVE_FIELDS, MAX_WAVES))
        n = self.waves
        out[_K, :n] = k
        out[_OMEGA, :n] = omega
        out[_PHASE, :n] = np.asarray(phases_rad, dtype=float)
        out[_F_COS, :n], out[_F_SIN, :n] = scale * heave.real, scale * heave.imag
        out[_M_COS, :n], out[_M_SIN, :n] = scale * pitch.real, scale * pitch.imag
        out[_F_MEAN, :n], out[_M_MEAN, :n] = mean * mean_heave, mean * mean_pitch
        if self.encounter_frequency:
            # Per unit speed (module docstring): the added-mass half (a_33 = rho S, half of the 2 rho S
            # integrals) times K / omega, and the moment's u int a_33 w dx, with the wave's vertical
            # velocity w = Re(i A omega e^(i(psi + K x))).
            added_heave, added_pitch = 0.5 * heave, 0.5 * pitch
            per_speed = k / omega
            force = per_speed * scale * added_heave
            moment = per_speed * scale * added_pitch + 1j * amplitude * omega * added_heave
            out[_F_SPEED_COS, :n], out[_F_SPEED_SIN, :n] = force.real, force.imag
            out[_M_SPEED_COS, :n], out[_M_SPEED_SIN, :n] = moment.real, moment.imag
        return out

    def mean_suction(
        self,
        depth_m: ArrayLike,
        hull_x_m: ArrayLike,
        hull_breadth_m: ArrayLike,
        density_kg_m3: float,
        gravity_m_s2: float,
    ) -> tuple[FloatArray, FloatArray]:
        """The expected second-order mean heave force [N, down positive] and pitch moment [N m] at
        depth ``depth_m``: the spectral integral int (rho S + a_33) K omega^2 2 S(omega) e^(-2 K h)
        d omega over the hull, by the bins' midpoints (the waves of a sea with every jitter 1/2)."""
        comps = self.components(
            np.full(self.waves, 0.5),
            np.zeros(self.waves),
            hull_x_m,
            hull_breadth_m,
            density_kg_m3,
            gravity_m_s2,
        )[:, : self.waves]
        h = np.asarray(depth_m, dtype=float)[..., None]
        decay = np.exp(-2.0 * comps[_K] * h)
        return -(comps[_F_MEAN] * decay).sum(-1), (comps[_M_MEAN] * decay).sum(-1)


def hull_wave_integrals(
    k: ArrayLike, hull_x_m: ArrayLike, hull_breadth_m: ArrayLike, density_kg_m3: float
) -> tuple[FloatArray, FloatArray, float, float]:
    """Int 2 rho S e^(i K x) dx and int 2 rho S x e^(i K x) dx for each K [1/m] (complex, [kg/m], [kg]), and
    int 2 rho S dx [kg/m], int 2 rho S x dx [kg] (S = pi b^2 / 4: circular sections with a_33 = rho S).

    By the trapezoid rule on the hull's stations refined 8 times (b linear between stations)."""
    x = np.asarray(hull_x_m, dtype=float)
    b = np.asarray(hull_breadth_m, dtype=float)
    order = np.argsort(x)
    x, b = x[order], b[order]
    fine = np.concatenate([np.linspace(x[i], x[i + 1], 9)[:-1] for i in range(x.size - 1)] + [x[-1:]])
    section = 2.0 * density_kg_m3 * 0.25 * math.pi * np.interp(fine, x, b) ** 2
    kk = np.asarray(k, dtype=float)[..., None]
    phase = np.exp(1j * kk * fine)
    heave = np.trapezoid(section * phase, fine, axis=-1)
    pitch = np.trapezoid(section * fine * phase, fine, axis=-1)
    return heave, pitch, float(np.trapezoid(section, fine)), float(np.trapezoid(section * fine, fine))


def encounter_factor(omega_radps: ArrayLike, speed_mps: ArrayLike, gravity_m_s2: float) -> FloatArray:
    """omega_e / omega = 1 + omega u / g [-]: how much faster a head sea's deep-water wave of frequency
    ``omega_radps`` meets a boat at ``speed_mps``, the factor on its diffraction force (module docstring)."""
    return 1.0 + np.asarray(omega_radps, dtype=float) * np.asarray(speed_mps, dtype=float) / gravity_m_s2


@inline_kernel
def wave_term(
    t: float, distance: float, depth: float, u: float, waves: FloatArray, i: int
) -> tuple[float, float]:
    """Wave ``i``'s (heave force [N, up positive], pitch moment [N m, nose-up positive]) at time ``t`` [s],
    distance travelled ``distance`` [m], depth ``depth`` [m] and speed ``u`` [m/s], first order plus the
    second-order mean: a term of :func:`wave_force_point`'s sum. (Under :mod:`subenv.jax` ``i`` is the
    array of every column's index: one trace computes all the terms at once.)"""
    k = waves[_K, i]
    psi = k * distance + waves[_OMEGA, i] * t + waves[_PHASE, i]
    c, s = math.cos(psi), math.sin(psi)
    decay = math.exp(-k * depth)
    # (the forward-speed terms after the zero-speed ones: a sea without them, all 0.0, adds exactly 0.0)
    up = decay * (waves[_F_COS, i] * c - waves[_F_SIN, i] * s + decay * waves[_F_MEAN, i]) + u * decay * (
        waves[_F_SPEED_COS, i] * c - waves[_F_SPEED_SIN, i] * s
    )
    nose_up = decay * (
        waves[_M_COS, i] * c - waves[_M_SIN, i] * s + decay * waves[_M_MEAN, i]
    ) + u * decay * (waves[_M_SPEED_COS, i] * c - waves[_M_SPEED_SIN, i] * s)
    return up, nose_up


@inline_kernel
def wave_force_point(
    t: float, distance: float, depth: float, u: float, waves: FloatArray, n: Static[int]
) -> tuple[float, float]:
    """The sea's heave force [N, down positive] and pitch moment [N m, nose-up positive] on the hull at
    time ``t`` [s], distance travelled ``distance`` [m], depth ``depth`` [m] and speed ``u`` [m/s]: the
    first ``n`` waves of ``waves`` (:meth:`SeaState.components`), first order plus the second-order mean
    (:func:`wave_term`, summed in the order of the columns); (0.0, 0.0) with ``n`` = 0. (``n`` is static
    for :mod:`subenv.jax`, which passes the columns of ``waves``.)"""
    if n == 0:
        return 0.0, 0.0
    up = 0.0
    nose_up = 0.0
    for i in range(n):
        wave_up, wave_nose_up = wave_term(t, distance, depth, u, waves, i)
        up += wave_up
        nose_up += wave_nose_up
    return -up, nose_up
