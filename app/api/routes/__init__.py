"""Routers of the HTTP API, one per concept (classify/explain, motion, presets, health, landing)."""
