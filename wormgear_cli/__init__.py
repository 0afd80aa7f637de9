"""wormgear-cli: accuracy of two-stage worm + spur gear drives."""

__version__ = "0.1.0"
