"""The two-shape scene: a pair of ellipses/ellipsoids, their motion, timeline, panel and witnesses."""
