"""``wormgear simulate``: (being built)."""
