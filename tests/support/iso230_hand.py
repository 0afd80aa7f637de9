"""A hand-worked ISO 230-2 table: target, direction -> the five runs' deviations [arcsec]."""

# --- a hand-worked ISO 230-2 example -------------------------------------------------------------------------
# 3 targets x 3 runs x 2 directions, deviations in arcsec chosen so every figure is a small number:
#   target   0 deg: up  1, 2, 3 -> mean  2, s 1 | down -2, 0, 2 -> mean 0, s 2
#   target 120 deg: up  4, 4, 4 -> mean  4, s 0 | down  0, 1, 2 -> mean 1, s 1
#   target 240 deg: up -3,-1, 1 -> mean -1, s 2 | down  0, 3, 6 -> mean 3, s 3
# (s with n - 1: e.g. 1, 2, 3 -> sum of squares 2 / 2 = 1; 0, 3, 6 -> 18 / 2 = 9 -> s = 3)
HAND = {
    (0.0, 1): (1, 2, 3), (0.0, -1): (-2, 0, 2),
    (120.0, 1): (4, 4, 4), (120.0, -1): (0, 1, 2),
    (240.0, 1): (-3, -1, 1), (240.0, -1): (0, 3, 6),
}
