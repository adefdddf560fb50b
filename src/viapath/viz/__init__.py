"""Plots and animations of episodes (matplotlib is imported only when drawing)."""
