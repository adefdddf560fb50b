"""Laser perception: scanner model, ray casting, fusion, detection, circle fits and tracking.

The core (everything but :mod:`~viapath.perception.laser`, which plugs into the simulator, and
:mod:`~viapath.perception.commands`, the CLI) is pure numpy and runs on a robot as it is.
"""

from viapath.perception.detection import DetectorParams, Detections, detect
from viapath.perception.scanner import ScannerModel, paper_scanners, sanitize_ranges
from viapath.perception.tracking import MultiTargetTracker, TrackerParams

__all__ = ["DetectorParams", "Detections", "LaserPerception", "MultiTargetTracker", "ScannerModel", "TrackerParams",
           "detect", "paper_scanners", "sanitize_ranges", "tracking_errors"]


def __getattr__(name):  # LaserPerception pulls in the simulator's interface: import it only on demand
    if name in ("LaserPerception", "tracking_errors"):
        from viapath.perception import laser

        return getattr(laser, name)
    raise AttributeError(name)
