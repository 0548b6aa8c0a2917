"""Collisions between bodies: ball with ball, and ball with any other particle (cloth or cube).

Resolved once per step, after the integrator's update and the terrain impacts (in finish_step),
like terrain impacts and for the same reason: stages stay smooth functions of the state. For each
overlapping pair (a, b) that the broad phase finds, with n the unit vector from b to a,
penetration p = r_a + r_b - |x_a - x_b| and w = 1/m (zero for a pinned particle):

- if the pair approaches (v_rel . n < 0, v_rel = v_a - v_b), the normal impulse
      j = -(1 + e) (v_rel . n) / (w_a + w_b)
  changes v_a by +w_a j n and v_b by -w_b j n;
- ball-particle pairs also get Coulomb friction: a tangential impulse against the sliding velocity
  v_T that stops the sliding if at most mu j suffices, else has size mu j;
- the overlap shrinks by ``position_correction`` p along n, shared in proportion to the inverse
  masses so that the centre of mass stays where it is.

Each impulse acts on both particles with opposite signs, so momentum is conserved in every
collision (up to rounding); a pinned particle (w = 0) is an immovable wall. Contacts are resolved
one after the other in the broad phase's canonical order; each rereads the current positions and
skips a pair that earlier corrections already separated.

Restitution e, friction mu and the correction are the Balls body's: a ball-particle pair uses the
ball's ``particle_restitution``, ``particle_friction`` and ``position_correction``; a ball-ball pair
the mean of the two balls' ``ball_restitution`` and ``position_correction``, with no friction.

Every integrator runs this pass, unchanged. The explicit ones take steps small enough for it to
be all the ball-particle contact there is. Backward Euler (implicit_euler) takes steps so large
that its solve would pull cloth into a ball faster than the correction pushes it out, so it also
has ball-particle contacts as penalty springs inside its solve (implicit/ball_contact.py); this
pass then finds only what the penalty leaves: a small penetration and little approach speed.
The penalty is inelastic and frictionless and takes part of the approach speed in the solve, so
under backward Euler ``particle_restitution`` reflects only what is left: a 10 kg ball hitting a
free 2 kg point at 3 m/s with e = 0.5 separates at 1.0 m/s rather than 1.5 (with e = 0 it
separates at 0.008 m/s, the penalty pushing out the last of the overlap).
"""
import math

from ._jit import kernel
from .broadphase import find_contacts


@kernel
def resolve_body_collisions(model, x, v):
    """Resolve every ball-ball and ball-particle contact of the state (x, v) in place."""
    if model.balls.shape[0] == 0:
        return
    pairs = find_contacts(x, model.radius, model.balls, model.ball_slot)
    for k in range(pairs.shape[0]):
        a, b = pairs[k, 0], pairs[k, 1]
        ball, other = model.ball_slot[a], model.ball_slot[b]
        if other >= 0:
            restitution = 0.5 * (model.ball_restitution[ball] + model.ball_restitution[other])
            correction = 0.5 * (model.position_correction[ball] + model.position_correction[other])
            friction = 0.0
        else:
            restitution = model.particle_restitution[ball]
            correction = model.position_correction[ball]
            friction = model.particle_friction[ball]
        collide(x, v, model.inv_mass, model.radius, a, b, restitution, friction, correction)


@kernel
def collide(x, v, inv_mass, radius, a, b, restitution, friction, correction):
    """One contact between particles a and b (see the module docstring)."""
    w_a, w_b = inv_mass[a], inv_mass[b]
    w = w_a + w_b
    if w == 0.0:
        return  # two pinned particles: nothing can move
    dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    penetration = radius[a] + radius[b] - distance
    if not penetration > 0.0:
        return  # separated by an earlier contact's correction (or not finite)
    if distance > 0.0:
        nx, ny, nz = dx / distance, dy / distance, dz / distance
    else:
        nx, ny, nz = 0.0, 1.0, 0.0  # concentric: any direction separates them; choose up
    rx, ry, rz = v[a, 0] - v[b, 0], v[a, 1] - v[b, 1], v[a, 2] - v[b, 2]
    approach = rx * nx + ry * ny + rz * nz
    if approach < 0.0:
        j = -(1.0 + restitution) * approach / w
        # tangential relative velocity; the normal impulse leaves it unchanged
        tx, ty, tz = rx - approach * nx, ry - approach * ny, rz - approach * nz
        sliding = math.sqrt(tx * tx + ty * ty + tz * tz)
        # share of v_T that friction removes: all of it (sticking) if mu j can, else mu j w / |v_T|
        limit = friction * j * w
        stop = 1.0 if sliding <= limit else limit / sliding
        # impulse on a: j n - stop v_T / w  (b receives the opposite)
        ix, iy, iz = j * nx - stop * tx / w, j * ny - stop * ty / w, j * nz - stop * tz / w
        v[a, 0] += w_a * ix
        v[a, 1] += w_a * iy
        v[a, 2] += w_a * iz
        v[b, 0] -= w_b * ix
        v[b, 1] -= w_b * iy
        v[b, 2] -= w_b * iz
    shift = correction * penetration / w
    x[a, 0] += w_a * shift * nx
    x[a, 1] += w_a * shift * ny
    x[a, 2] += w_a * shift * nz
    x[b, 0] -= w_b * shift * nx
    x[b, 1] -= w_b * shift * ny
    x[b, 2] -= w_b * shift * nz
