"""The moving world's tables, built once per model: the motions of the moving terrains and of
the pins that move, their poses at time 0, and each moving pin's particles (world.py moves
them as time goes)."""
import numpy as np

from .bodies.pins import followed_terrain
from .motion import CENTRE_PART, PIVOT_PART, POSE, ROTATION_PART, Motion, pack_motions
from .rivets import riveted_paths


def pack_world(terrains, built, offsets) -> dict:
    """The model's arrays of the moving world: the motions of the moving terrains (in the
    order of their terrain_motion rows) and of the pins that move (bodies/pins.py), their
    poses at time 0, and each moving pin's particles. A pin that follows a terrain moving
    rigidly takes that terrain's row; one that follows a deforming terrain a path of its own for
    each particle (rivets.py); one that follows a still terrain holds, as a pin without motion
    does."""
    motions = [(terrain.motion, terrain.anchor()) for terrain in terrains
               if terrain.motion is not None]
    rows = {t: r for r, t in enumerate(t for t, terrain in enumerate(terrains)
                                       if terrain.motion is not None)}
    particles, rows_of_pins, placed, stiffness, damping = [], [], [], [], []
    for body, start in zip(built, offsets):
        for chosen, pin, paths in body.moving_pins:
            where, followed = body.positions[chosen], followed_terrain(pin)
            if paths is None and followed >= 0 and terrains[followed].deforms():
                # each riveted to its nearest triangle
                paths = riveted_paths(terrains[followed].deforming_surface(), where)
            if paths is not None:   # an animation: a path of its own for each particle
                row = np.arange(len(motions), len(motions) + len(chosen))
                motions += [(path, anchor) for path, anchor in zip(paths, where)]
            elif pin.motion is not None or rows.get(followed, -1) < 0:
                # its own motion, or it holds (a soft pin, or one following a still terrain)
                if pin.motion is None and pin.stiffness is None:
                    continue   # a hard pin that holds: its particles have no mass to move
                row = len(motions)
                motions.append((pin.motion or Motion(), where.mean(axis=0)))
            else:
                terrain, row = terrains[followed], rows[followed]
                # they keep the place they start at in the terrain's frame: where that place
                # was when the terrain was placed, x = R0^T (x_start - c0) + pivot
                pose = terrain.motion.pose(0.0, terrain.anchor())
                where = ((where - pose[CENTRE_PART]) @ pose[ROTATION_PART].reshape(3, 3)
                         + pose[PIVOT_PART])
            particles.append(chosen + start)
            rows_of_pins.append(np.broadcast_to(np.asarray(row, np.int64), len(chosen)))
            placed.append(where)
            soft = pin.stiffness is not None
            stiffness.append(np.full(len(chosen), float(pin.stiffness) if soft else 0.0))
            damping.append(np.full(len(chosen), float(pin.damping) if soft else 0.0))
    info, keys = pack_motions(motions)
    poses = np.array([motion.pose(0.0, anchor) for motion, anchor in motions]).reshape(-1, POSE)
    return {"motion_info": info, "motion_keys": keys, "motion_pose": poses,
            "pin_particles": np.concatenate([np.zeros(0, np.int64)] + particles),
            "pin_motion": np.concatenate([np.zeros(0, np.int64)] + rows_of_pins),
            "pin_placed": np.concatenate([np.zeros((0, 3))] + placed),
            "pin_stiffness": np.concatenate([np.zeros(0)] + stiffness),
            "pin_damping": np.concatenate([np.zeros(0)] + damping)}
