"""The many-bodies scene: bodies from files or uploads, their contacts, and the sweep of moving bodies."""
