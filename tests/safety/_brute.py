"""Independent brute-force reference for the shield's admissibility (docs/design.md §7), for the tests only.

Written from the definition, not from the shield's code: the drive is stepped as the simulator steps
it (the commanded (v, ω) reached through the acceleration limits once per control period, then held),
the unicycle is integrated with fine midpoint steps (``fine`` per period), and at every fine time the
robot centre is tested against every person's forecast disc as a point-in-disc test. Vectorised over
many cases and commands at once so that 10 000 cycles run in seconds.

Shapes: B cases, K commands per case, N people per case (padded with far-away people).
"""

from __future__ import annotations

import numpy as np


def _towards(x, y, heading, t, people, speed, slack):
    """(L, K, N): robot velocity . (q - robot) > -slack |v| |r| at time t for some point q the person's centre
    may be at: within spread(t) = k σ_p + k σ_v t + a_p t²/2 of the forecast centre."""
    px, py, vx, vy, spread_sigma, spread_growth, accel = people
    dx = x[..., None] - (px + vx * t)[:, None, :]
    dy = y[..., None] - (py + vy * t)[:, None, :]
    along = -(speed * np.cos(heading))[..., None] * dx - (speed * np.sin(heading))[..., None] * dy
    spread = spread_sigma + spread_growth * t + 0.5 * accel * t * t  # (L, N)
    along = along + np.abs(speed)[..., None] * spread[:, None, :]
    return along > -slack * speed[..., None] * np.sqrt(dx * dx + dy * dy)


def brute_admissible(
    case: dict,
    commands: np.ndarray,
    extra_m: float = 0.0,
    fine: int = 8,
    friendly: bool = False,
    towards_only: bool = True,
    towards_slack: float = 0.0,
    towards_in_period: bool = True,
) -> np.ndarray:
    """(B, K) bool: command k of case b is admissible (and friendly, if asked) with radii grown by ``extra_m``.

    ``towards_only``: a meeting counts only when the robot's velocity has a positive component towards
    some point the person's centre may be at (within k σ_p + k σ_v t + a_p t²/2 of the forecast centre) (more than ``-towards_slack`` |v| |r|: a robust check counts
    near-perpendicular motion too) at that instant or at any earlier one of the same control period,
    its start included: the at-fault metric reads the heading at the start of the period in which a
    contact begins. ``towards_in_period=False`` reads it at the instant of the meeting only (a weaker rule,
    for the test that shows the difference). ``case`` holds arrays: x, y, heading, speed, turn (B,), radius (B,), vmax, amax, wmax, alphamax,
    dt (B,), margin, accel_p, k_sigma (B,), people positions P (B,N,2), velocities V (B,N,2),
    radii r (B,N), sigma_v (B,N), sigma_p (B,N). ``commands`` (B, K, 2).
    """
    c = {key: np.asarray(value, dtype=float) for key, value in case.items()}
    b_count, k_count = commands.shape[:2]
    col = lambda name: c[name][:, None]  # (B, 1)
    # What one period of each command achieves (the drive's limits), then the braking recurrence.
    v_cmd = np.clip(commands[..., 0], 0.0, col("vmax"))
    w_cmd = np.clip(commands[..., 1], -col("wmax"), col("wmax"))
    dv, dw = col("amax") * col("dt"), col("alphamax") * col("dt")
    speed = col("speed") + np.clip(v_cmd - col("speed"), -dv, dv)
    turn = col("turn") + np.clip(w_cmd - col("turn"), -dw, dw)
    x = np.broadcast_to(col("x"), (b_count, k_count)).copy()
    y = np.broadcast_to(col("y"), (b_count, k_count)).copy()
    heading = np.broadcast_to(col("heading"), (b_count, k_count)).copy()
    # People: separation at t of robot centre to person centre, against the forecast radius.
    gap0 = np.hypot(c["x"][:, None] - c["P"][..., 0], c["y"][:, None] - c["P"][..., 1]) - c["radius"][:, None] - c["r"]
    # margin + k sigma_p, at most the present gap (the disc never holds the robot at t = 0 unless touching)
    static = np.minimum(c["margin"][:, None] + c["k_sigma"][:, None] * c["sigma_p"], np.maximum(gap0, 0.0))
    # (less 1e-9 m: a person inside the margin sits exactly on its disc's edge at t = 0, and two ways of
    # rounding the same number must not decide a test)
    base = c["radius"][:, None] + c["r"] + static + extra_m - 1e-9  # (B, N)
    grow = c["k_sigma"][:, None] * c["sigma_v"]
    ok = np.ones((b_count, k_count), dtype=bool)
    ok &= ~np.any(gap0 <= 0.0, axis=1)[:, None]  # touching now: nothing is admissible
    t = np.zeros((b_count, 1))
    h = col("dt") / fine
    # At rest = speed 0 at the start of a period and during it: the first standing period still counts
    # as moving, at the speed it began with (``previous``).
    previous = np.broadcast_to(col("speed"), (b_count, k_count)).copy()
    moving = (speed != 0.0) | (previous != 0.0)
    rest_x, rest_y, rest_t = x.copy(), y.copy(), np.zeros((b_count, k_count))
    steps = 0
    while np.any(moving):
        live = np.flatnonzero(moving.any(axis=1))  # cases still braking: only those are stepped
        mv, sp, tr = moving[live], speed[live], turn[live]
        s_eff = np.maximum(np.abs(sp), np.abs(previous[live]))
        px, py, vx, vy = c["P"][live, :, 0], c["P"][live, :, 1], c["V"][live, :, 0], c["V"][live, :, 1]
        b_l, g_l, a_l, h_l = base[live], grow[live], c["accel_p"][live, None], h[live]
        xl, yl, hl, tl, okl = x[live], y[live], heading[live], t[live], ok[live]
        spread_sigma = (c["k_sigma"][:, None] * c["sigma_p"])[live]
        people = (px, py, vx, vy, spread_sigma, g_l, a_l)

        def towards_now(xl, yl, hl, tl, people=people, s_eff=s_eff):
            return _towards(xl, yl, hl, tl, people, s_eff, towards_slack)

        towards_in_period_so_far = towards_now(xl, yl, hl, tl)  # (L, K, N), from the period's start
        for _ in range(fine):
            mid = hl + 0.5 * tr * h_l
            xl = xl + np.where(mv, sp * h_l * np.cos(mid), 0.0)
            yl = yl + np.where(mv, sp * h_l * np.sin(mid), 0.0)
            hl = hl + tr * h_l
            tl = tl + h_l
            radius = b_l + g_l * tl + 0.5 * a_l * tl * tl  # (L, N)
            dx = xl[..., None] - (px + vx * tl)[:, None, :]
            dy = yl[..., None] - (py + vy * tl)[:, None, :]
            inside = dx * dx + dy * dy < (radius * radius)[:, None, :]
            if towards_only:  # robot velocity . (person centre - robot) > 0 (robust: > -slack |v| |r|)
                if towards_in_period:
                    towards_in_period_so_far |= towards_now(xl, yl, hl, tl)
                    inside &= towards_in_period_so_far
                else:
                    inside &= towards_now(xl, yl, hl, tl)
            okl &= ~(mv & np.any(inside, axis=2))
        x[live], y[live], heading[live], t[live], ok[live] = xl, yl, hl, tl, okl
        rest_x, rest_y = np.where(moving, x, rest_x), np.where(moving, y, rest_y)
        rest_t = np.where(moving, t, rest_t)
        # the next period: the stop command, through the same limits
        previous = speed
        speed = speed + np.clip(-speed, -dv, dv)
        turn = turn + np.clip(-turn, -dw, dw)
        moving = moving & ((speed != 0.0) | (previous != 0.0))
        steps += 1
        if steps > 10_000:
            raise RuntimeError("braking never ends")
    if not friendly:
        return ok
    # Friendly: from the robot's rest time on, the person brakes at accel_p along its forecast velocity;
    # sample its braking path densely and test the robot's rest position against its disc then.
    a = np.maximum(c["accel_p"], 1e-3)[:, None]  # (B, 1)
    speed_p = np.hypot(c["V"][..., 0], c["V"][..., 1])  # (B, N)
    unit = c["V"] / np.where(speed_p > 0, speed_p, 1.0)[..., None]
    for f in np.linspace(0.0, 1.0, 200):
        tau = f * speed_p / a  # (B, N)
        along = speed_p * tau - 0.5 * a * tau * tau
        ts = rest_t[..., None]  # (B, K, 1)
        cx = c["P"][:, None, :, 0] + c["V"][:, None, :, 0] * ts + unit[:, None, :, 0] * along[:, None, :]
        cy = c["P"][:, None, :, 1] + c["V"][:, None, :, 1] * ts + unit[:, None, :, 1] * along[:, None, :]
        radius = base[:, None, :] + grow[:, None, :] * ts + 0.5 * c["accel_p"][:, None, None] * ts * ts
        d = np.hypot(rest_x[..., None] - cx, rest_y[..., None] - cy)
        ok &= ~np.any(d < radius, axis=2)
    return ok


def window_grid(case: dict, n: int) -> np.ndarray:
    """A dense (n x n) grid of commands over each case's dynamic window, (B, n*n, 2)."""
    speed, turn = np.asarray(case["speed"], float), np.asarray(case["turn"], float)
    dv = np.asarray(case["amax"], float) * np.asarray(case["dt"], float)
    dw = np.asarray(case["alphamax"], float) * np.asarray(case["dt"], float)
    v_lo, v_hi = np.maximum(speed - dv, 0.0), np.minimum(speed + dv, np.asarray(case["vmax"], float))
    w_lo = np.maximum(turn - dw, -np.asarray(case["wmax"], float))
    w_hi = np.minimum(turn + dw, np.asarray(case["wmax"], float))
    f = np.linspace(0.0, 1.0, n)
    v = v_lo[:, None] + (v_hi - v_lo)[:, None] * f
    w = w_lo[:, None] + (w_hi - w_lo)[:, None] * f
    grid = np.stack(np.broadcast_arrays(v[:, :, None], w[:, None, :]), axis=-1)
    return grid.reshape(len(speed), n * n, 2)
