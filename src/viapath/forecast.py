"""Pedestrian forecasts and their displacement errors, numpy only (core: goes on a robot).

Forecasts, from a person's observed positions at a fixed row step ``dt_s``:

* :func:`constant_velocity_forecast` — what the planner uses today: the velocity is a backward
  difference over one row step of past positions (as :func:`viapath.io.eth_ucy.replay_states`
  gives it, and as a tracker reports it), held constant: ``x(t + k dt) = x(t) + k (x(t) - x(t - dt))``.
* :func:`social_force_forecast` — the same desired velocity, but every person seen at the last
  observed instant is rolled out jointly under Helbing & Molnár's social force (Phys. Rev. E 51,
  1995, Eq. 2-4 and 8, as :mod:`viapath.sim.social_force`; re-implemented here since the core
  imports no simulator): relaxation towards the observed velocity with ``tau``, elliptic repulsion
  ``V0/sigma exp(-b/sigma)`` from the others (surface distances, radius 0.25 m each), field of view
  ±100° (weight 0.5 behind), speed capped at 1.3 × the observed speed (at least 0.5 m/s). Choices the
  paper leaves open: semi-implicit Euler at ``step_s`` ≈ 0.2 s (h/tau ≤ 0.4); people not yet seen (entering later)
  are unknown to the forecast, as they are to a robot; a person seen at only one instant (no
  velocity) is taken as standing.
* :func:`heading_uncertainty_samples` — constant velocity with the heading perturbed by
  ``N(0, sigma_heading)`` (Schöller et al., "What the constant velocity model can teach us about
  pedestrian motion prediction", RA-L 2020: CVM-S); :func:`velocity_sigma_mps` turns the same idea
  into the per-person velocity σ that :class:`viapath.observation.Obstacles` carries
  (``sigma_v = sigma_0 + sigma_heading |v|``: lateral spread of a heading error, plus a floor).

Errors (the usual ETH/UCY protocol of Social-LSTM / Social-GAN / Trajectron++): windows of 20 rows
(8 observed, 12 predicted; one window per starting row, stride one row); a person is scored in a
window when present in all 20 rows; windows with fewer than two such people are dropped (S-GAN's
``min_ped = 1``). ADE = mean over the 12 predicted rows of the Euclidean error, FDE = error at the
last one; a scene's figure is the mean over all scored (window, person) pairs. The protocol counts
rows, not seconds, so ``biwi_eth.txt`` (2/3 s per row, data README) is scored on the same 8/12 rows
(5.3 s observed, 8 s predicted): the constant-velocity forecast does not depend on ``dt_s`` (it
cancels), the social force integrates in real time with ``dt_s = 2/3 s``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

OBSERVED_ROWS = 8
PREDICTED_ROWS = 12


# -- the usual ETH/UCY windows ---------------------------------------------------------------------


@dataclass(frozen=True)
class Window:
    """One protocol window: the scored people's observed and future rows, and everyone seen."""

    observed: np.ndarray  # (N, OBS, 2) scored people, rows t-OBS+1 .. t
    future: np.ndarray  # (N, PRED, 2) rows t+1 .. t+PRED
    seen_last: np.ndarray  # (M, 2) everyone present at the last observed row (scored people first)
    seen_previous: np.ndarray  # (M, 2) their position one row earlier (NaN when not present then)


def protocol_windows(
    table: np.ndarray,
    observed_rows: int = OBSERVED_ROWS,
    predicted_rows: int = PREDICTED_ROWS,
    min_people: int = 2,
) -> Iterator[Window]:
    """Yield the protocol's :class:`Window` s of a 4-column table ``frame id x y`` (rows sorted or not).

    Frames are taken on the file's own grid: the distinct frames, in order (as S-GAN does); a window
    is ``observed_rows + predicted_rows`` consecutive distinct frames.
    """
    table = np.asarray(table, dtype=float)
    if table.ndim != 2 or table.shape[1] != 4:
        raise ValueError(f"expected a (rows, 4) table 'frame id x y', got shape {table.shape}")
    frames = np.unique(table[:, 0])
    ids = np.unique(table[:, 1])
    frame_index = np.searchsorted(frames, table[:, 0])
    id_index = np.searchsorted(ids, table[:, 1])
    grid = np.full((len(frames), len(ids), 2), np.nan)
    grid[frame_index, id_index] = table[:, 2:4]
    length = observed_rows + predicted_rows
    for start in range(len(frames) - length + 1):
        block = grid[start : start + length]
        full = np.all(np.isfinite(block[..., 0]), axis=0)
        if full.sum() < min_people:
            continue
        last = observed_rows - 1
        present = np.isfinite(block[last, :, 0])
        others = present & ~full
        order = np.concatenate([np.flatnonzero(full), np.flatnonzero(others)])
        yield Window(
            observed=block[:observed_rows, full].transpose(1, 0, 2),
            future=block[observed_rows:, full].transpose(1, 0, 2),
            seen_last=block[last, order],
            seen_previous=block[last - 1, order] if last >= 1 else np.full((len(order), 2), np.nan),
        )


def displacement_errors(predicted: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ADE and FDE per person: ``predicted`` and ``truth`` (N, PRED, 2) → two arrays (N,), metres."""
    predicted, truth = np.asarray(predicted, float), np.asarray(truth, float)
    if predicted.shape != truth.shape or predicted.ndim != 3 or predicted.shape[-1] != 2:
        raise ValueError(f"predicted {predicted.shape} and truth {truth.shape} must both be (N, steps, 2)")
    error = np.linalg.norm(predicted - truth, axis=-1)
    return error.mean(axis=1), error[:, -1]


# -- constant velocity (today's planner) -------------------------------------------------------------


def backward_velocity(last: np.ndarray, previous: np.ndarray, dt_s: float) -> np.ndarray:
    """Velocity over one row step, from past positions only; 0 where ``previous`` is unknown (NaN)."""
    velocity = (np.asarray(last, float) - np.asarray(previous, float)) / float(dt_s)
    return np.where(np.isfinite(velocity), velocity, 0.0)


def constant_velocity_forecast(observed: np.ndarray, steps: int, dt_s: float) -> np.ndarray:
    """``observed`` (N, H ≥ 2, 2) at row step ``dt_s`` → (N, steps, 2) held at the last row's velocity."""
    observed = np.asarray(observed, float)
    velocity = backward_velocity(observed[:, -1], observed[:, -2], dt_s)
    k = np.arange(1, steps + 1) * float(dt_s)
    return observed[:, -1, None, :] + k[None, :, None] * velocity[:, None, :]


# -- constant velocity with heading uncertainty -------------------------------------------------------


def heading_uncertainty_samples(
    observed: np.ndarray, steps: int, dt_s: float, sigma_heading_rad: float, samples: int, rng: np.random.Generator
) -> np.ndarray:
    """CVM-S: (samples, N, steps, 2), each person's velocity turned by one ``N(0, sigma)`` angle per sample."""
    observed = np.asarray(observed, float)
    velocity = backward_velocity(observed[:, -1], observed[:, -2], dt_s)
    angle = rng.normal(0.0, sigma_heading_rad, (samples, len(observed)))
    c, s = np.cos(angle), np.sin(angle)
    turned = np.stack(
        [c * velocity[None, :, 0] - s * velocity[None, :, 1], s * velocity[None, :, 0] + c * velocity[None, :, 1]],
        axis=-1,
    )
    k = np.arange(1, steps + 1) * float(dt_s)
    return observed[None, :, -1, None, :] + k[None, None, :, None] * turned[:, :, None, :]


def velocity_sigma_mps(velocities: np.ndarray, sigma_floor_mps: float, sigma_heading_rad: float) -> np.ndarray:
    """Per-person velocity σ for :class:`viapath.observation.Obstacles`: ``sigma_0 + sigma_heading |v|``."""
    speed = np.hypot(*np.asarray(velocities, float).reshape(-1, 2).T)
    return float(sigma_floor_mps) + float(sigma_heading_rad) * speed


# -- social force ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class SocialForecastParams:
    relaxation_time_s: float = 0.5  # tau
    strength_m2ps2: float = 2.1  # V0
    range_m: float = 0.3  # sigma
    step_time_s: float = 2.0  # Δt of Eq. 4
    radius_m: float = 0.25
    field_of_view_rad: float = np.radians(100.0)
    outside_view_weight: float = 0.5
    max_speed_factor: float = 1.3
    min_speed_cap_mps: float = 0.5
    step_s: float = 0.2


def elliptic_repulsion(
    positions: np.ndarray,
    velocities: np.ndarray,
    shrink_m: np.ndarray | float,
    potential: tuple[float, float, float],
    view: tuple[float, float],
) -> np.ndarray:
    """Helbing's elliptic repulsion summed over b on each a (N, 2): ``shrink_m`` (scalar or (N, N)) off each
    centre distance, ``potential`` V0, σ, Δt of Eq. 4, forces outside the ``view`` (half-angle, weight) weighed
    less (Eq. 8). For the social-force forecast and the simulated crowd."""
    strength_m2ps2, range_m, step_time_s = potential
    if len(positions) < 2 or strength_m2ps2 == 0.0:
        return np.zeros_like(positions)
    field_of_view_rad, outside_view_weight = view
    r = positions[:, None, :] - positions[None, :, :]  # r_ab = r_a - r_b, (N, N, 2)
    # Surface distance, expressed as a centre distance for the point-pedestrian formula.
    centre = np.hypot(r[..., 0], r[..., 1])
    r = r * np.where(centre > 1e-9, np.maximum(centre - shrink_m, 1e-3) / np.maximum(centre, 1e-9), 1.0)[..., None]
    s = velocities[None, :, :] * step_time_s  # v_b dt e_b, (1, N, 2)
    r_norm = np.maximum(np.hypot(r[..., 0], r[..., 1]), 1e-9)
    rs = r - s
    rs_norm = np.maximum(np.hypot(rs[..., 0], rs[..., 1]), 1e-9)
    b = np.maximum(0.5 * np.sqrt(np.maximum((r_norm + rs_norm) ** 2 - np.sum(s * s, axis=-1), 1e-12)), 1e-6)
    grad_b = ((r_norm + rs_norm) / (4.0 * b))[..., None] * (r / r_norm[..., None] + rs / rs_norm[..., None])
    force = (strength_m2ps2 / range_m * np.exp(-b / range_m))[..., None] * grad_b  # along +grad b (away from b)
    idx = np.arange(len(positions))
    force[idx, idx] = 0.0  # no self-interaction
    speed = np.hypot(velocities[:, 0], velocities[:, 1])
    heading = np.where(speed[:, None] > 1e-9, velocities / np.maximum(speed, 1e-9)[:, None], 0.0)
    f_norm = np.hypot(force[..., 0], force[..., 1])
    in_view = np.sum(heading[:, None, :] * (-force), axis=-1) >= f_norm * np.cos(field_of_view_rad)
    weight = np.where(in_view | (speed[:, None] <= 1e-9), 1.0, outside_view_weight)
    return np.sum(weight[..., None] * force, axis=1)


def social_force_forecast(
    last: np.ndarray, previous: np.ndarray, steps: int, dt_s: float, params: SocialForecastParams | None = None
) -> np.ndarray:
    """Joint roll-out of everyone seen: ``last`` / ``previous`` (M, 2) positions at the last two rows
    (``previous`` NaN: standing) → (M, steps, 2) at row times. Desired velocity: the observed one."""
    params = params or SocialForecastParams()
    position = np.asarray(last, float).copy()
    desired = backward_velocity(last, previous, dt_s)
    velocity = desired.copy()
    desired_speed = np.hypot(desired[:, 0], desired[:, 1])
    cap = np.maximum(params.max_speed_factor * desired_speed, params.min_speed_cap_mps)
    substeps = max(1, int(round(dt_s / params.step_s)))
    h = dt_s / substeps
    out = np.empty((len(position), steps, 2))
    for k in range(steps):
        for _ in range(substeps):
            accel = (desired - velocity) / params.relaxation_time_s + elliptic_repulsion(
                position,
                velocity,
                2.0 * params.radius_m,
                (params.strength_m2ps2, params.range_m, params.step_time_s),
                (params.field_of_view_rad, params.outside_view_weight),
            )
            velocity = velocity + h * accel
            speed = np.hypot(velocity[:, 0], velocity[:, 1])
            velocity *= np.where(speed > cap, cap / np.maximum(speed, 1e-12), 1.0)[:, None]
            position = position + h * velocity
        out[:, k] = position
    return out
