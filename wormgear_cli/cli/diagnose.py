"""``wormgear diagnose``: (being built)."""
