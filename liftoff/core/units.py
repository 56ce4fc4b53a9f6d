"""Exact definitions of the non-SI units liftoff meets, as SI values: standard gravity (load
factors in g, the pad's 1 g) and the inch and pound of inch-pound-second models and reports.
One copy for every layer (reduction.nastran's unit systems, analysis.units' report units,
the load factors, the slosh modes' default g_eff)."""
G0 = 9.80665                # m/s^2, standard gravity (exact, 3rd CGPM 1901)
INCH = 0.0254               # m, exact (international inch, 1959)
FOOT = 0.3048               # m, exact (12 in)
POUND = 0.45359237          # kg, exact (international avoirdupois pound, 1959)
LBF = POUND * G0            # N, exact: 4.4482216152605 (pound-force)
