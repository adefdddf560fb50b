"""Subcommands of the viapath CLI that live beside the main app (each registers itself with ``register(app)``)."""
