"""What the adjoint covers, checked before the work (``check_supported``) and after the forward
run (``check_contact_free``), each a one-line SceneError.

Covered: symplectic_euler, explicit_euler, rk4 and implicit_euler (adjoints.py), springs,
dampers, gravity, drag, the wind on surfaces and balls (wind.py), pins that hold, move or are
soft (pins.py) and attachments, soft or hard (attachments.py); contact with planes, spheres,
bowls and meshes, still or moving rigidly (contact.py, implicit_contact.py), and with deforming
meshes under the explicit methods (contact.py); body-body contact
of surfaces (a self-colliding body's own too) and of balls with balls and particles under
every integrator (body_contact.py, implicit_bodies.py). Not yet covered, so refused rather than
given a gradient that leaves a force out: contact with deforming meshes under implicit_euler,
and there hard attachments on bodies that touch a terrain or each other
and a fold that closes within a step that touches a terrain (adjoints.py and
implicit_contact.py refuse these at that step). A terrain the adjoint does not
follow may be in the scene as long as no particle comes within its contact band during the
run (``contact_check``).
"""
import numpy as np

from ..errors import SceneError
from .adjoints import ADJOINTS
from .clock import STEP_START, at_time


def check_supported(simulation) -> None:
    name = simulation.integrator.name
    if name not in ADJOINTS:
        raise SceneError("integrator", name, "has no adjoint yet: gradients run under "
                         + ", ".join(ADJOINTS))


def contact_check(simulation, physical=None):
    """A function ``check(step, (x, v))`` that refuses a state in which some particle is within
    the contact band of a terrain the adjoint does not follow (or would be within the step, as
    implicit_euler's constraints look ahead); None if it follows them all. The backward pass
    calls it on every step's start, with ``physical``'s clock there: a terrain that moves or
    deforms is looked up where it is at the step's start and end (without ``physical``, where
    the scene placed it)."""
    from .contact import Planes
    from .terrain_shapes import Deforming, Moving

    model = simulation.model
    shapes = (Planes.of(model) if physical is None else physical.planes).shapes
    implicit = simulation.integrator.name == "implicit_euler"
    followed = [shape is not None and not (implicit and isinstance(shape, Deforming))
                for shape in shapes]
    covered = ("planes, spheres, bowls and meshes, still or moving rigidly, only under "
               "implicit_euler (deforming meshes too under the explicit methods)" if implicit
               else "planes, spheres, bowls and meshes, still, moving rigidly or deforming, "
               "only")
    if all(followed):
        return None
    radii = model.arrays.terrain_offset
    h = simulation.dt

    def check(step, state):
        x, v = state[0], state[1]
        for t, terrain in enumerate(model.terrains):
            if followed[t]:
                continue
            if isinstance(shapes[t], Moving) and physical is not None:
                at_time(physical, 0.0)
                phi = shapes[t].distance(x, radii)
                at_time(physical, h)
                reach = shapes[t].distance(x + h * v, radii)
            elif model.arrays.terrain_deforming[t] >= 0 and physical is not None:
                now = physical.clock[STEP_START]
                phi = deformed_distance(terrain, x, radii, now)
                reach = deformed_distance(terrain, x + h * v, radii, now + h)
            else:
                phi = terrain.signed_distance(x, radii)
                reach = phi + h * np.minimum(_normal_speed(terrain, x, v, radii), 0.0)
            touching = (np.minimum(phi, reach) < model.arrays.terrain_epsilon[t]) & ~model.pinned
            if touching.any():
                raise SceneError(f"terrains.{t}", type(terrain).__name__,
                                 f"is touched at step {step} (particle "
                                 f"{int(np.argmax(touching))}): gradients follow contact with "
                                 + covered)
    return check


def deformed_distance(terrain, x, radii, t):
    """Signed distance (m) from each particle's surface to a deforming mesh terrain where its
    animation has it at time t (s): libigl's, as MeshTerrain.signed_distance's at time 0."""
    import igl

    from ..terrains.deforming_mesh import surface_at

    surface = terrain.deforming_surface()
    return igl.signed_distance(np.asarray(x, float), surface_at(surface, t), surface.triangles,
                               sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0] - radii


def _normal_speed(terrain, x, v, radii):
    """v . n, n the terrain's normal by differences of its distance (any terrain kind)."""
    step = 1e-6
    normal = np.stack([(terrain.signed_distance(x + step * e, radii)
                        - terrain.signed_distance(x - step * e, radii)) / (2 * step)
                       for e in np.eye(3)], axis=1)
    return np.einsum("ij,ij->i", v, normal)
