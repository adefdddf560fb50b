"""The simulator: robot kinematics, obstacle motion, perception, the closed loop and its metrics."""
