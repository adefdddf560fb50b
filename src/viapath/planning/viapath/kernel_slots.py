"""The slots of the choice kernel's two settings arrays (:func:`.kernels.choose` and its halves): named once,
for the kernels that read them and the planner that fills them (this module imports no numba, so the planner
can).

``settings`` (float64, ``F_COUNT``) and ``integers`` (int64, ``C_COUNT``). numba compiles these numbers into
the kernels as constants and its cache does not notice a change here: after changing one, delete the
kernels' cache files (``__pycache__/kernels.*.nbi``, ``*.nbc``) or point ``NUMBA_CACHE_DIR`` somewhere new.
"""

# integers: the episode's (filled once per planner: _kernel_constants) ...
C_NOMINAL, C_SEGMENT, C_SUBGOAL, C_DEPTH, C_ROOT_LIMIT, C_ROLLOUTS, C_STEPS, C_DEGREES, C_PREFERRED = range(9)
C_SLOW = 9  # whether slow/wait candidates are grown (slow_times_s not empty)
# ... and the cycle's: try the paper's step 1; last cycle's choice (way: 3 slots, speed in mm/s); only one way.
C_TRY_STRAIGHT, C_PREVIOUS, C_PREV_WAY, C_PREV_MMPS, C_ONLY, C_ONLY_WAY = 10, 11, 12, 15, 16, 17
C_COUNT = 20

# settings: Eq. 1's weights and the critics' (k1..k4, side preference, hysteresis), the nominal speed, ...
F_K1, F_K2, F_K3, F_K4, F_SIDE, F_HYSTERESIS, F_NOMINAL, F_ROLLOUT_HEADING, F_ACCEL, F_DT = range(10)
# ... the motion limits and the controller, the corridor check's spacing (the episode's); and the cycle's: how far
# short of a blocked subgoal legs end, the horizon, the corridor tolerance.
F_TURN_RATE, F_TURN_ACCEL, F_SPEED, F_GAIN, F_TURN_IN_PLACE = range(10, 15)
F_STOP_SHORT, F_HORIZON, F_SPACING, F_TOLERANCE = range(15, 19)
F_COUNT = 19

# What choose_tree found (the first entry of its ``found``).
NO_CANDIDATE, STEP_ONE, CANDIDATES = 0, 1, 2
