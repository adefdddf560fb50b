"""Perception models as the simulator knows them (kept for older imports): the interface lives in
:mod:`viapath.perception.base`, the oracle in :mod:`viapath.perception.oracle`, the laser chain in
:mod:`viapath.perception.laser`, and the modes by name in :mod:`viapath.perception.modes`."""

from viapath.perception.base import Perception, WorldSnapshot
from viapath.perception.oracle import OraclePerception

__all__ = ["OraclePerception", "Perception", "WorldSnapshot"]
