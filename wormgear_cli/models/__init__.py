"""Physics of the drive as pure, numpy-vectorised functions (no I/O).

Every function states its equation, units and source in its docstring.
Internal units: lengths [mm], forces [N], moduli [N/mm^2], angles [rad],
temperatures [degC], time [s], torque [N*m].
"""
