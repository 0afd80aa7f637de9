"""``wormgear sweep``: (being built)."""
