"""Routers of the HTTP API, one per concept (classify/explain, motion, witness, contacts, sweep, presets, health, landing)."""
