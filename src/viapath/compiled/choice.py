"""The option that chooses the arithmetic, ``compute`` (the planner's and the shield's): its name, default,
choices and help, written here once, next to the policy that reads it (:func:`viapath.compiled.resolve`).

``compute`` was called ``backend`` before; a YAML file or ``--option`` that still says ``backend`` is read as
``compute`` with a FutureWarning (:attr:`viapath.options.Option.former_names`). It never changes a decision,
only how fast it is made, so a run's identity leaves it out (``decides=False``).
"""

from __future__ import annotations

from viapath.compiled import COMPUTE_CHOICES
from viapath.options import Option

NAME = "compute"
FORMER_NAME = "backend"


def compute_option(help: str) -> Option:
    """The ``compute`` option (``auto``, ``numpy`` or ``numba``; default ``auto``) with its owner's help."""
    return Option(NAME, "auto", help, choices=COMPUTE_CHOICES, former_names=(FORMER_NAME,), decides=False)


PLANNER_COMPUTE = compute_option(
    "arithmetic of the hot path: auto = compiled (numba, extra 'fast') when numba is "
    "importable, else numpy; the decisions are the same"
)
SHIELD_COMPUTE = compute_option(
    "arithmetic of the shield's test: auto = compiled (numba, extra 'fast') once it is "
    "compiled (viapath bench and the ROS 2 node compile it, ~12 s once per machine), else numpy (env "
    "VIAPATH_PLANNER_BACKEND overrides auto, as for the planner); the verdicts are the same"
)
