"""Laser perception: scanner model, ray casting, fusion, detection, circle fits and tracking.

numpy, with its hot loops compiled (:mod:`viapath.jit`): it runs on a robot as it is.
:mod:`~viapath.perception.base` is the interface the closed loop calls, :mod:`~viapath.perception.modes`
the modes by name (oracle, laser).
"""

from viapath.perception.detection import Detections, DetectorParams, detect
from viapath.perception.laser import LaserPerception, tracking_errors
from viapath.perception.scanner import ScannerModel, paper_scanners, sanitize_ranges
from viapath.perception.tracking import MultiTargetTracker, TrackerParams

__all__ = [
    "Detections",
    "DetectorParams",
    "LaserPerception",
    "MultiTargetTracker",
    "ScannerModel",
    "TrackerParams",
    "detect",
    "paper_scanners",
    "sanitize_ranges",
    "tracking_errors",
]
