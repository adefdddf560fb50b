"""Readers for recorded data: pedestrian trajectories (ETH/UCY) and laser scans (ROS bags)."""
