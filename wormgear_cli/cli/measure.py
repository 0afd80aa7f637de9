"""``wormgear measure``: (being built)."""
