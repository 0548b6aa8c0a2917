"""Stiffness presets: the raw numbers an artist starts from, per role.

A cloth preset is springsim's ``[bodies.material]`` (density in kg/m², stretch, shear and bend in
N/m per unit strain, their dampings in N s/m), so that it behaves alike at any mesh resolution;
a jelly-body preset the lattice springs' ``ks`` (N/m) and ``kd`` (N s/m). The cotton preset is
springsim's default material and the jelly preset its default mesh body.
"""
CLOTH = {
    # name: (density, stretch, shear, bend, stretch_damping, shear_damping, bend_damping)
    "SILK": (0.08, 2000.0, 100.0, 2.0, 0.2, 0.02, 0.0005),
    "COTTON": (0.3, 5000.0, 500.0, 50.0, 0.5, 0.05, 0.005),
    "DENIM": (0.45, 20000.0, 2000.0, 300.0, 1.0, 0.1, 0.02),
    "LEATHER": (0.8, 50000.0, 8000.0, 2000.0, 2.0, 0.3, 0.1),
}
BODY = {
    # name: (ks, kd) of the structural, shear and bend springs alike
    "JELLY": (2000.0, 60.0),
    "RUBBER": (10000.0, 150.0),
}
CLOTH_KEYS = ("density", "stretch", "shear", "bend", "stretch_damping", "shear_damping",
              "bend_damping")
ITEMS = [(name, name.title(), f"{name.title()} ({'cloth' if name in CLOTH else 'jelly body'})")
         for name in (*CLOTH, *BODY)] + [("CUSTOM", "Custom", "the raw numbers below")]


def apply(settings, name: str) -> None:
    """Copy preset ``name``'s numbers into an object's springsim settings."""
    if name in CLOTH:
        for key, value in zip(CLOTH_KEYS, CLOTH[name]):
            setattr(settings, key, value)
    elif name in BODY:
        settings.spring_ks, settings.spring_kd = BODY[name]
