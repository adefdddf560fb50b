"""The record layouts of the planner's compiled steps, named once: the slots of the choice's two settings arrays
(:func:`.selection.choose` and its halves), the columns of the candidate tree's node store (:mod:`.tree`) and
the entries of what the choice hands back. The compiled steps read these names, and the rest of the planner
reads the records through :mod:`.packing` (:class:`.packing.NodeStore`, :class:`.packing.CompiledChoice`),
never by number.
"""

# integers: the episode's (filled once per planner: _kernel_constants) ...
C_NOMINAL, C_SEGMENT, C_SUBGOAL, C_DEPTH, C_ROOT_LIMIT, C_ROLLOUTS, C_STEPS, C_DEGREES, C_PREFERRED = range(9)
C_SLOW = 9  # whether slow/wait candidates are grown (slow_times_s not empty)
# ... and the cycle's: try the paper's step 1; last cycle's choice (its way round: obstacle, side, root, and its
# speed in mm/s); only one way round allowed (obstacle, side, root).
C_TRY_STRAIGHT, C_PREVIOUS = 10, 11
C_PREV_OBSTACLE, C_PREV_SIDE, C_PREV_ROOT, C_PREV_MMPS = 12, 13, 14, 15
C_ONLY, C_ONLY_OBSTACLE, C_ONLY_SIDE, C_ONLY_ROOT = 16, 17, 18, 19
C_COUNT = 20

# settings: Eq. 1's weights and the critics' (k1..k4, side preference, hysteresis), the nominal speed, ...
F_K1, F_K2, F_K3, F_K4, F_SIDE, F_HYSTERESIS, F_NOMINAL, F_ROLLOUT_HEADING, F_ACCEL, F_DT = range(10)
# ... the motion limits and the controller, the corridor check's spacing (the episode's); and the cycle's: how far
# short of a blocked subgoal legs end, the horizon, the corridor tolerance.
F_TURN_RATE, F_TURN_ACCEL, F_SPEED, F_GAIN, F_TURN_IN_PLACE = range(10, 15)
F_STOP_SHORT, F_HORIZON, F_SPACING, F_TOLERANCE = range(15, 19)
# ... the cost of standing still per second, and the creep speed of slow/wait candidates (0: none).
F_STANDING, F_CREEP = 19, 20
F_COUNT = 21

# The node store of the candidate tree (grow, choose_tree): floats (M, NODE_FLOATS): position, time, speed,
# path length, first direction (unit x, y), slow/wait time and speed, length left to the subgoal; ...
N_X, N_Y, N_TIME, N_SPEED, N_LENGTH, N_FIRST_X, N_FIRST_Y, N_SLOW_S, N_SLOW_SPEED, N_TO_GOAL = range(10)
NODE_FLOATS = 10
# ... integers (M, NODE_INTEGERS): parent node (-1 for a root), way round (obstacle, side, root), leaf flag.
N_PARENT, N_OBSTACLE, N_SIDE, N_ROOT, N_LEAF = range(5)
NODE_INTEGERS = 5

# What choose_tree found (``found``): its status, whether step 1 turns on the spot, then the K leaves' nodes.
FOUND_STATUS, FOUND_TURN_IN_PLACE, FOUND_LEAVES = 0, 1, 2
NO_CANDIDATE, STEP_ONE, CANDIDATES = 0, 1, 2  # the status
# What choose_candidate ranks (``ranking``, after ``found`` in choose's first array): the first rank that
# follows (-1: none tried follows), R the ranks, then the order (R candidates) and each rank's can_follow (R).
RANKING_FIRST, RANKING_COUNT, RANKING_ORDER = 0, 1, 2
# Its costs (COST_ROWS, K): the six critics' terms (critics_for's order), their sum E, E with only_way applied.
COST_TERMS, COST_SUM, COST_TOTAL, COST_ROWS = 6, 6, 7, 8
