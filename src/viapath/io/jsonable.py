"""Values made fit for strict JSON: NaN and infinities become ``null`` (JSON has neither), numpy scalars
and arrays become Python numbers and lists. What ``--json`` prints and result files hold go through here."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def dumps(value: Any, **kwargs) -> str:
    """``json.dumps`` of :func:`jsonable` ``(value)``, refusing NaN (none is left)."""
    return json.dumps(jsonable(value), allow_nan=False, **kwargs)
