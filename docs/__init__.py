"""Documentation helpers (python -m docs.make_images regenerates the screenshots)."""
