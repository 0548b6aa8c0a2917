"""The colours of everything drawn (RGB in [0, 1]); springs use the course framework's colours."""
from ..springs import SpringKind

SPRING_COLORS = {
    SpringKind.STRUCTURAL: (0.0, 0.85, 0.9),   # cyan
    SpringKind.SHEAR: (0.95, 0.85, 0.1),       # yellow
    SpringKind.BEND: (0.2, 0.8, 0.25),         # green
    SpringKind.FACE: (0.75, 0.35, 0.9),        # violet: the long face-to-face springs
}
BODY_COLORS = ((0.95, 0.55, 0.2), (0.25, 0.55, 0.95), (0.9, 0.35, 0.55), (0.55, 0.8, 0.3))
CLOTH_BACK_COLOR = (0.35, 0.6, 0.85)        # the underside of an open surface (cloth)
PARTICLE_COLOR = (0.15, 0.15, 0.2)
BALL_COLOR = (0.6, 0.62, 0.7)
# terrains darker than the pale sky, so that every face of stairs or a slope shows
TERRAIN_COLOR = (0.5, 0.5, 0.47)
TERRAIN_CHECKER_COLORS = ((0.7, 0.72, 0.68), (0.56, 0.58, 0.54))
BOWL_COLOR = (0.55, 0.68, 0.78)
PIN_COLOR = (0.55, 0.1, 0.15)               # pinned particles, larger than the others
WIND_COLOR = (0.2, 0.3, 0.75)               # the arrow along the wind
CONTACT_COLOR = (0.85, 0.1, 0.1)             # body-body contact points
CONTACT_NORMAL_COLOR = (0.1, 0.1, 0.1)       # and their normals
BACKGROUND_COLOR = (0.75, 0.8, 0.86)         # a pale blue once polyscope has tone-mapped it
LABEL_COLOR = (40, 40, 48)                    # the time label on video frames, 8-bit RGB
