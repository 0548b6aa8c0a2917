"""The adjoint's clock, ``physical.clock``: the time of the step it is at and the time of the
force evaluation it is taking, as the forward's model.clock holds them (world.py). The
backward pass (tape.backward) sets the step's start; each adjoint sets the force time before
every evaluation (``at_time``), as the forward's stages move the world: the wind and the pins'
paths are functions of it."""

STEP_START, FORCE_TIME = 0, 1


def at_time(physical, offset):
    """Set the force time to the step's start plus ``offset`` (s)."""
    physical.clock[FORCE_TIME] = physical.clock[STEP_START] + offset
