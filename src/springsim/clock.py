"""The slots of ``model.clock`` (s), which the integrators and the world's kernels share so that
no kernel signature carries the time (world.py): the time the call starts at, the time of the
step (or part of one) being taken, the time the world was last moved to, and the whole step's
start, end and size."""

CALL_START, STAGE_TIME, WORLD_TIME, STEP_START, STEP_END, STEP_SIZE = range(6)
SLOTS = 6
