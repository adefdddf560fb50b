"""Multi-target tracking of detected obstacles in the world frame: constant-velocity Kalman filters.

Source: the constant-velocity (white-noise acceleration) model and Kalman filter of Bar-Shalom,
Li, Kirubarajan, "Estimation with Applications to Tracking and Navigation" (2001), §6.3.2:
``F = [[I, dt I], [0, I]]``, ``Q = q [[dt³/3 I, dt²/2 I], [dt²/2 I, dt I]]`` with ``q = σ_a²``;
global-nearest-neighbour association with a chi-square gate on the innovation (§3.2 / docs/design.md §3),
optimal assignment when tracks compete (:mod:`~viapath.perception.assignment`); M-of-N confirmation.

What we chose where the source leaves it open:
* State per track ``(x, y, vx, vy)`` in the world frame. Detections come in the robot frame and are
  moved to the world with the odometry pose (the snapshot pose in the simulator), so the robot's own
  motion never appears as obstacle motion.
* A new track starts at the detection with zero velocity and ``initial_velocity_sigma_mps`` (1 m/s,
  a walking person) — no two-point initialisation: the filter learns the velocity in 3–5 updates.
* Gate: Mahalanobis distance² ≤ ``gate_chi2`` (13.8 = 99.9 % for 2 d.o.f.: at 10 Hz a 99 % gate
  loses a true detection every 10 s) *and* Euclidean distance ≤ ``gate_distance_m`` (a cap for
  young tracks whose covariance is still wide).
* ``q = σ_a²`` with ``σ_a = acceleration_sigma_mps2 = 0.2 m/s²``: on a walker measured with 2–3 cm
  noise, velocity RMSE ≈ 0.08 m/s after 1 s (0.5 m/s² gives ≈ 0.15 m/s, 0.1 gives 0.05 but lags
  turns). Real people turn and the legs swing: the ``scans`` command uses 0.5.
* An unmatched detection closer than ``spawn_exclusion_m`` to an existing track does not start a
  new track (it is that track's outlier or a second fragment of the same object; a new track
  there would compete with the old one for its detections). Should two tracks still come within
  ``track_merge_distance_m`` of each other with velocities within
  ``track_merge_velocity_difference_mps`` (two partial views of one object beside the robot), the
  one with fewer hits is deleted; people crossing each other differ in velocity and are kept.
* Confirmation: ``confirm_hits`` hits (M) among the last ``confirm_window`` cycles (N); a tentative
  track that can no longer make it, or that is unseen for ``tentative_max_unseen_s``, is dropped. A
  confirmed track is dropped after ``max_unseen_s`` without a detection; until then it coasts on
  its prediction (an occluded person does not vanish) and its covariance grows.
* What is reported (:meth:`MultiTargetTracker.people`): the confirmed tracks and, given the robot's
  position, every tentative track within ``report_tentative_within_m`` (1.5 m) of it, from its first
  detection: someone who appears that close cannot wait two cycles for confirmation (at 1.7 m/s
  towards a robot at 0.3 m/s, 1.3 m shrink to 0.9 m by then). A track born on its first detection is
  reported standing with ``initial_velocity_sigma_mps`` (1 m/s): a cone that covers a walker going any
  way, so planner and shield slow down. Farther away one-off clutter still needs confirmation (a laser's
  false positives do not stop the robot); so does a tentative track whose disc overlaps a confirmed
  track's (a fragment of that person: two people do not overlap) or, given the static geometry known so
  far, that geometry (the detector starts tentative tracks on the corners of boxes and carts).
* Settled velocity: the velocity reported is that of a second filter on the same detections with a
  much smaller process noise (``settled_acceleration_sigma_mps2`` = 0.02 m/s²: a walker's steady
  pace), so that a person walking steadily is forecast steadily (with 3 cm detections the agile
  filter's velocity wanders by ≈ 0.07 m/s from cycle to cycle, enough to flip a planner between
  trailing a walker and passing them). When that filter's innovation leaves its gate
  (``settled_gate_chi2``, 9.21: 99 % for 2 d.o.f.) the person changed pace or direction, and it
  restarts from the agile filter's state and covariance. Association, confirmation, the position and
  standing still use the agile filter.
* Radius: an exponential average of the detections' radii (``radius_smoothing``).
* Reported uncertainty: ``position_sigma_m`` and ``velocity_sigma_mps`` are the square roots of the
  largest eigenvalue of the position / velocity blocks of the agile filter's covariance (worst
  direction); the velocity's has the gap between the two filters' velocities added in quadrature
  (while the settled velocity lags a change of pace, the gap is what it may be off by).
* Standing still: a confirmed track whose estimate stays within ``static_radius_m`` of where it
  stopped, slower than ``static_wake_speed_mps``, for ``static_after_s`` is *static* (a box, a cart or
  a pillar the detector took for a person, or a person standing). :meth:`people` leaves it out and no
  longer explains its returns, so they reach the static layer and are kept clear of as geometry
  instead of as a person who may start walking at any moment. It is still tracked, and is a person
  again the cycle its estimate leaves that circle or its speed passes ``static_wake_speed_mps``
  (a person starting at 1 m/s² from rest has moved 0.1 m after 0.45 s). ``static_after_s`` = inf turns
  this off. :meth:`obstacles` reports every confirmed track, static or not (what the ``scans``
  command lists).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import cast

import numpy as np

from viapath.observation import Obstacles
from viapath.perception.assignment import gated_assignment
from viapath.static import StaticLayer, point_segment_distances


@dataclass(frozen=True)
class TrackerParams:
    acceleration_sigma_mps2: float = 0.2
    initial_velocity_sigma_mps: float = 1.0
    gate_chi2: float = 13.8
    spawn_exclusion_m: float = 0.3
    track_merge_distance_m: float = 0.25
    track_merge_velocity_difference_mps: float = 0.5
    gate_distance_m: float = 1.0
    confirm_hits: int = 3
    confirm_window: int = 5
    max_unseen_s: float = 1.0
    tentative_max_unseen_s: float = 0.25
    radius_smoothing: float = 0.3
    static_after_s: float = 3.0
    static_radius_m: float = 0.1
    static_wake_speed_mps: float = 0.3
    settled_acceleration_sigma_mps2: float = 0.02
    settled_gate_chi2: float = 9.21
    report_tentative_within_m: float = 1.5

    def __post_init__(self) -> None:
        if not 1 <= self.confirm_hits <= self.confirm_window <= 62:
            raise ValueError("need 1 <= confirm_hits <= confirm_window <= 62")
        for name in (
            "acceleration_sigma_mps2",
            "initial_velocity_sigma_mps",
            "gate_chi2",
            "gate_distance_m",
            "max_unseen_s",
            "tentative_max_unseen_s",
            "static_radius_m",
            "static_wake_speed_mps",
            "settled_acceleration_sigma_mps2",
            "settled_gate_chi2",
        ):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be finite and > 0, got {value}")
        if not (np.isfinite(self.report_tentative_within_m) and self.report_tentative_within_m >= 0):
            raise ValueError(f"report_tentative_within_m must be finite and >= 0, got {self.report_tentative_within_m}")
        if not self.static_after_s > 0:  # inf allowed: never static
            raise ValueError(f"static_after_s must be > 0 (inf: never), got {self.static_after_s}")


@dataclass(frozen=True)
class Track:
    """A read-only view of one track (for plots, CSV output and tests)."""

    track_id: int
    position: np.ndarray
    velocity: np.ndarray
    covariance: np.ndarray  # (4, 4)
    radius_m: float
    confirmed: bool
    hits: int
    last_seen_s: float

    @property
    def speed_mps(self) -> float:
        return float(np.hypot(*self.velocity))


class MultiTargetTracker:
    """Tracks held as arrays (one row per track) so that predict and update are vectorised."""

    def __init__(self, params: TrackerParams = TrackerParams()):
        self.params = params
        self.reset()

    def reset(self) -> None:
        self.state = np.zeros((0, 4))
        self.covariance = np.zeros((0, 4, 4))
        self.settled_state = np.zeros((0, 4))  # the settled filter (low process noise): its velocity is reported
        self.settled_covariance = np.zeros((0, 4, 4))
        self.ids = np.zeros(0, dtype=int)
        self.radii_m = np.zeros(0)
        self.history = np.zeros(0, dtype=np.int64)  # bit k = hit k cycles ago
        self.hits = np.zeros(0, dtype=int)
        self.age = np.zeros(0, dtype=int)  # cycles since birth (1 at birth)
        self.confirmed = np.zeros(0, dtype=bool)
        self.last_seen_s = np.zeros(0)
        self.still_at = np.zeros((0, 2))  # where each track's estimate last stopped moving
        self.still_since_s = np.zeros(0)
        self.static = np.zeros(0, dtype=bool)
        self.time_s: float | None = None
        self.next_id = 0

    def __len__(self) -> int:
        return len(self.ids)

    # -- the filter --------------------------------------------------------------------------
    def predict(self, time_s: float) -> None:
        if self.time_s is None:
            self.time_s = float(time_s)
            return
        dt = float(time_s) - self.time_s
        if dt < 0:
            raise ValueError(f"time went backwards: {self.time_s} -> {time_s}")
        self.time_s = float(time_s)
        if dt == 0 or len(self.ids) == 0:
            return
        f, qm = _motion_model(dt, self.params.acceleration_sigma_mps2)
        self.state = self.state @ f.T
        self.covariance = f @ self.covariance @ f.T + qm
        _, qs = _motion_model(dt, self.params.settled_acceleration_sigma_mps2)
        self.settled_state = self.settled_state @ f.T
        self.settled_covariance = f @ self.settled_covariance @ f.T + qs

    def step(
        self, time_s: float, positions: np.ndarray, sigmas_m: np.ndarray, radii_m: np.ndarray
    ) -> list[tuple[int, int]]:
        """Predict to ``time_s``, associate world-frame detections, update, create and delete tracks.

        Returns the (track row before deletion, detection) pairs that were associated.
        """
        positions = np.asarray(positions, dtype=float).reshape(-1, 2)
        sigmas_m = _per_detection(sigmas_m, len(positions))
        radii_m = _per_detection(radii_m, len(positions))
        self.predict(time_s)
        p = self.params
        n_tracks, n_det = len(self.ids), len(positions)
        pairs: list[tuple[int, int]] = []
        if n_tracks and n_det:
            innovation = positions[None, :, :] - self.state[:, None, :2]  # (T, D, 2)
            s = self.covariance[:, None, :2, :2] + (sigmas_m[None, :, None, None] ** 2) * _EYE2
            det = s[..., 0, 0] * s[..., 1, 1] - s[..., 0, 1] * s[..., 1, 0]
            ix, iy = innovation[..., 0], innovation[..., 1]
            d2 = (s[..., 1, 1] * ix * ix - 2 * s[..., 0, 1] * ix * iy + s[..., 0, 0] * iy * iy) / det
            distance = np.hypot(ix, iy)
            cost = np.where(distance <= p.gate_distance_m, d2, np.inf)
            pairs = gated_assignment(cost, p.gate_chi2)
        self.history = (self.history << 1) & ((1 << p.confirm_window) - 1)
        if pairs:
            rows = np.array([a for a, _ in pairs])
            cols = np.array([b for _, b in pairs])
            self._update(rows, positions[cols], sigmas_m[cols])
            self._update_settled(rows, positions[cols], sigmas_m[cols])
            self.radii_m[rows] += p.radius_smoothing * (radii_m[cols] - self.radii_m[rows])
            self.history[rows] |= 1
            self.hits[rows] += 1
            self.last_seen_s[rows] = self.time_s
        self.age += 1
        recent_hits = _popcount(self.history)
        self.confirmed |= recent_hits >= p.confirm_hits
        # Deletion: confirmed tracks after max_unseen_s; tentative ones when they cannot be confirmed
        # within their first confirm_window cycles any more, or are unseen too long.
        unseen = self.time_s - self.last_seen_s  # type: ignore[operator]  # set just above
        cycles_left = np.maximum(p.confirm_window - self.age, 0)
        hopeless = ~self.confirmed & (
            (unseen > p.tentative_max_unseen_s + 1e-9) | (recent_hits + cycles_left < p.confirm_hits)
        )
        keep = np.where(self.confirmed, unseen <= p.max_unseen_s + 1e-9, ~hopeless)
        keep &= ~self._duplicates()
        self._keep(keep)
        matched = np.zeros(n_det, dtype=bool)
        if pairs:
            matched[cols] = True
        if len(self.ids) and p.spawn_exclusion_m > 0 and (~matched).any():
            gap = positions[:, None, :] - self.state[None, :, :2]
            matched |= np.hypot(gap[..., 0], gap[..., 1]).min(axis=1) < p.spawn_exclusion_m
        self._create(positions[~matched], sigmas_m[~matched], radii_m[~matched])
        self._mark_static()
        return pairs

    def _mark_static(self) -> None:
        """Restart the stillness clock of every track that moved; mark confirmed tracks still long enough."""
        p = self.params
        moved = np.hypot(*(self.state[:, :2] - self.still_at).T) > p.static_radius_m
        moved |= np.hypot(self.state[:, 2], self.state[:, 3]) > p.static_wake_speed_mps
        self.still_at[moved] = self.state[moved, :2]
        self.still_since_s[moved] = self.time_s
        still_s = cast(float, self.time_s) - self.still_since_s  # set by predict()
        self.static = self.confirmed & ~moved & (still_s >= p.static_after_s - 1e-9)

    def _update(self, rows, z, sigma) -> None:
        """Kalman update of tracks ``rows`` with position measurements ``z`` of isotropic noise ``sigma``."""
        self.state[rows], self.covariance[rows], _ = _kalman_update(self.state[rows], self.covariance[rows], z, sigma)

    def _update_settled(self, rows, z, sigma) -> None:
        """The settled filter's update; where its innovation leaves its gate (the person changed pace or
        direction), it restarts from the agile filter's state and covariance (just updated)."""
        x, cov, d2 = _kalman_update(self.settled_state[rows], self.settled_covariance[rows], z, sigma)
        off = d2 > self.params.settled_gate_chi2
        x[off], cov[off] = self.state[rows][off], self.covariance[rows][off]
        self.settled_state[rows], self.settled_covariance[rows] = x, cov

    def _duplicates(self) -> np.ndarray:
        """Tracks that sit on another track, moving alike: the one with fewer hits goes."""
        out = np.zeros(len(self.ids), dtype=bool)
        if len(self.ids) < 2 or self.params.track_merge_distance_m <= 0:
            return out
        gap = self.state[:, None, :2] - self.state[None, :, :2]
        close = np.hypot(gap[..., 0], gap[..., 1]) < self.params.track_merge_distance_m
        dv = self.state[:, None, 2:] - self.state[None, :, 2:]
        close &= np.hypot(dv[..., 0], dv[..., 1]) < self.params.track_merge_velocity_difference_mps
        np.fill_diagonal(close, False)
        if not close.any():
            return out
        for i, j in zip(*np.nonzero(np.triu(close)), strict=True):
            if out[i] or out[j]:
                continue
            weaker = j if (self.hits[i], -self.ids[i]) >= (self.hits[j], -self.ids[j]) else i
            out[weaker] = True
        return out

    def _keep(self, keep: np.ndarray) -> None:
        if keep.all():
            return
        for name in (
            "state",
            "covariance",
            "settled_state",
            "settled_covariance",
            "ids",
            "radii_m",
            "history",
            "hits",
            "age",
            "confirmed",
            "last_seen_s",
            "still_at",
            "still_since_s",
            "static",
        ):
            setattr(self, name, getattr(self, name)[keep])

    def _create(self, positions, sigmas, radii) -> None:
        n = len(positions)
        if n == 0:
            return
        state = np.zeros((n, 4))
        state[:, :2] = positions
        cov = np.zeros((n, 4, 4))
        cov[:, 0, 0] = cov[:, 1, 1] = sigmas**2
        cov[:, 2, 2] = cov[:, 3, 3] = self.params.initial_velocity_sigma_mps**2
        self.state = np.concatenate([self.state, state])
        self.covariance = np.concatenate([self.covariance, cov])
        self.settled_state = np.concatenate([self.settled_state, state])
        self.settled_covariance = np.concatenate([self.settled_covariance, cov])
        self.ids = np.concatenate([self.ids, np.arange(self.next_id, self.next_id + n)])
        self.next_id += n
        self.radii_m = np.concatenate([self.radii_m, radii])
        self.history = np.concatenate([self.history, np.ones(n, dtype=np.int64)])
        self.hits = np.concatenate([self.hits, np.ones(n, dtype=int)])
        self.age = np.concatenate([self.age, np.ones(n, dtype=int)])
        born = np.ones(n, dtype=bool) if self.params.confirm_hits <= 1 else np.zeros(n, dtype=bool)
        self.confirmed = np.concatenate([self.confirmed, born])
        self.last_seen_s = np.concatenate([self.last_seen_s, np.full(n, self.time_s)])
        self.still_at = np.concatenate([self.still_at, positions])
        self.still_since_s = np.concatenate([self.still_since_s, np.full(n, self.time_s)])
        self.static = np.concatenate([self.static, np.zeros(n, dtype=bool)])

    # -- output ------------------------------------------------------------------------------
    def sigmas(self) -> tuple[np.ndarray, np.ndarray]:
        """The reported position and velocity σ of every track (see :meth:`obstacles`)."""
        if len(self.ids) == 0:
            return np.zeros(0), np.zeros(0)
        c = self.covariance
        return _largest_sigma(c[:, 0, 0], c[:, 0, 1], c[:, 1, 1]), self._velocity_sigma(np.ones(len(self.ids), bool))

    def _velocity_sigma(self, rows: np.ndarray) -> np.ndarray:
        """The reported velocity σ of tracks ``rows``: the agile filter's, with the gap between the two filters'
        velocities added in quadrature (the settled velocity is reported; while it lags a change of pace the
        gap is what it may be off by)."""
        c = self.covariance[rows]
        gap = self.settled_state[rows, 2:] - self.state[rows, 2:]
        agile = _largest_sigma(c[:, 2, 2], c[:, 2, 3], c[:, 3, 3])
        return np.sqrt(agile * agile + gap[:, 0] * gap[:, 0] + gap[:, 1] * gap[:, 1])

    def people(self, robot_position=None, known_static: StaticLayer | None = None) -> Obstacles:
        """The people the planner and the shield receive: the confirmed tracks that are not static and, given
        the robot's position (world frame), the tentative tracks within ``report_tentative_within_m`` of it
        (see :meth:`reported`)."""
        return self.obstacles(rows=self.reported(robot_position, known_static))

    def reported(self, robot_position=None, known_static: StaticLayer | None = None) -> np.ndarray:
        """Which tracks :meth:`people` reports (a boolean row mask). A tentative track is left to its
        confirmation when its disc overlaps a confirmed track's (a fragment of that person) or static geometry
        already known (``known_static``: the detector starts tentative tracks on the corners of boxes and
        carts; a person does not stand inside a box)."""
        rows = self.confirmed & ~self.static
        within = self.params.report_tentative_within_m
        if robot_position is None or within <= 0 or self.confirmed.all():
            return rows
        gap = self.state[:, :2] - np.asarray(robot_position, dtype=float)[:2]
        near = ~self.confirmed & (np.hypot(gap[:, 0], gap[:, 1]) <= within)
        if near.any() and known_static is not None and len(known_static.segments):
            radii = known_static.radii_m if known_static.radii_m is not None else np.zeros(len(known_static.segments))
            clearance = point_segment_distances(self.state[near, :2], known_static.segments) - radii[None, :]
            near[near] = ~(clearance < self.radii_m[near, None]).any(axis=1)
        if near.any() and self.confirmed.any():
            # A tentative track whose disc overlaps a confirmed track's is a fragment of that person (two
            # people do not overlap): the confirmed track stands for it already.
            offset = self.state[near, None, :2] - self.state[None, self.confirmed, :2]
            touching = self.radii_m[near, None] + self.radii_m[None, self.confirmed]
            near[near] = ~(np.hypot(offset[..., 0], offset[..., 1]) < touching).any(axis=1)
        return rows | near

    def explaining(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, radii and confirmation of the tracks whose returns are a person's, not static
        geometry: every track that is not static (tentative ones too; the static layer does not let a
        tentative track clear what it remembers)."""
        rows = ~self.static
        return self.state[rows, :2], self.radii_m[rows], self.confirmed[rows]

    def obstacles(self, confirmed_only: bool = True, rows: np.ndarray | None = None) -> Obstacles:
        """Tracks as the planner's :class:`~viapath.observation.Obstacles` (world frame, at the last step's
        time): the confirmed ones (all with ``confirmed_only`` false), or the boolean selection ``rows``."""
        if rows is None:
            rows = self.confirmed if confirmed_only else np.ones(len(self.ids), dtype=bool)
        state, c = self.state[rows], self.covariance[rows]
        state[:, 2:] = self.settled_state[rows, 2:]  # the settled filter's velocity
        # The sigmas of the reported rows only (elementwise: the same values as sigmas()[rows]); every
        # array is fresh (boolean indexing copies), so Obstacles may keep them without copying again. The
        # positions and velocities are two column views of one such copy (not C-contiguous: the planner's
        # compiled path gets contiguous copies of them).
        return Obstacles.of_fresh_arrays(
            state[:, :2],
            state[:, 2:],
            self.radii_m[rows],
            _largest_sigma(c[:, 0, 0], c[:, 0, 1], c[:, 1, 1]),
            self._velocity_sigma(rows),
            self.ids[rows],
        )

    def tracks(self, confirmed_only: bool = False) -> list[Track]:
        return [
            Track(
                int(self.ids[i]),
                self.state[i, :2].copy(),
                self.settled_state[i, 2:].copy(),
                self.covariance[i].copy(),
                float(self.radii_m[i]),
                bool(self.confirmed[i]),
                int(self.hits[i]),
                float(self.last_seen_s[i]),
            )
            for i in range(len(self.ids))
            if self.confirmed[i] or not confirmed_only
        ]


_EYE2 = np.eye(2)


def _per_detection(values, n: int) -> np.ndarray:
    """``values`` as a float array of ``n`` (a scalar is repeated, read-only); an array already so is kept."""
    if type(values) is np.ndarray and values.dtype == np.float64 and values.shape == (n,):
        return values  # the common case (detections): np.broadcast_to would only add a read-only view
    return np.broadcast_to(np.asarray(values, dtype=float), (n,))


def _kalman_update(x: np.ndarray, cov: np.ndarray, z: np.ndarray, sigma: np.ndarray):
    """Kalman update of states ``x`` (R, 4) and covariances ``cov`` (R, 4, 4) with position measurements ``z``
    (R, 2) of isotropic noise ``sigma`` (R,): the new states and covariances, and each innovation's Mahalanobis
    distance² (R,).

    ``H = [I 0]``: ``S = P_pp + σ² I`` (2x2, inverted in closed form), ``K = P[:, :2] S⁻¹``,
    ``P' = P - K P[:2, :]`` (symmetrised).
    """
    var = sigma**2
    s00 = cov[:, 0, 0] + var
    s01 = cov[:, 0, 1]
    s11 = cov[:, 1, 1] + var
    det = s00 * s11 - s01 * s01
    s_inv = np.empty((len(x), 2, 2))
    s_inv[:, 0, 0] = s11 / det
    s_inv[:, 0, 1] = s_inv[:, 1, 0] = -s01 / det
    s_inv[:, 1, 1] = s00 / det
    gain = cov[:, :, :2] @ s_inv  # (R, 4, 2)
    innovation = z - x[:, :2]
    d2 = np.einsum("ri,rij,rj->r", innovation, s_inv, innovation)
    x = x + (gain @ innovation[..., None])[..., 0]
    cov = cov - gain @ cov[:, :2, :]
    return x, 0.5 * (cov + cov.transpose(0, 2, 1)), d2


@lru_cache(maxsize=8)
def _motion_model(dt: float, acceleration_sigma_mps2: float) -> tuple[np.ndarray, np.ndarray]:
    """``F`` and ``Q`` of the constant-velocity model for a step of ``dt`` (cached: the cycle time
    rarely changes; read-only, the callers only read them)."""
    q = acceleration_sigma_mps2**2
    a, b, c = q * dt**3 / 3, q * dt**2 / 2, q * dt
    f = np.array([[1.0, 0.0, dt, 0.0], [0.0, 1.0, 0.0, dt], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    qm = np.array([[a, 0.0, b, 0.0], [0.0, a, 0.0, b], [b, 0.0, c, 0.0], [0.0, b, 0.0, c]])
    f.flags.writeable = qm.flags.writeable = False
    return f, qm


def _largest_sigma(a, b, c):
    """Square root of the largest eigenvalue of the symmetric 2x2 matrices [[a, b], [b, c]]."""
    half_trace = 0.5 * (a + c)
    largest = half_trace + np.sqrt((0.5 * (a - c)) ** 2 + b * b)
    return np.sqrt(np.maximum(largest, 0.0))


def _popcount(values: np.ndarray) -> np.ndarray:
    if hasattr(np, "bitwise_count"):  # numpy >= 2.0
        return np.bitwise_count(values).astype(int)
    return np.array([bin(int(v)).count("1") for v in values], dtype=int)
