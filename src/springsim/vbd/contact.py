"""Terrain contact inside vertex block descent: an energy in the particle's position, so that the
minimization itself keeps particles out of terrains and holds them by friction.

Where a particle comes within ``delta`` of terrain t (phi < delta, phi its signed distance from
the particle's surface, n the terrain's normal, both where the terrain is at the step's end):

- normal: E = k/2 (delta - phi)^2, force lambda n with lambda = k (delta - phi), Hessian k n n^T.
  The stiffness is a multiple of the particle's own m/h^2 (``contact_stiffness_ratio``), so that
  the contact dominates its block at any mass and step: a particle pressed by its own weight sinks
  into the offset by g h^2 / ratio (2.8 micrometres at 1/60 s and the default ratio of 1,000);
- friction: a smoothed Coulomb law (IPC's, as VBD uses it), on the particle's motion this step
  relative to the surface, u = T ((x - x0) - h w) (T: the tangent plane, w the surface's
  velocity): force -mu lambda f1(|u|) u / |u| and Hessian mu lambda f1(|u|) / |u| T, where
  f1(s) = 2 s / e - s^2 / e^2 below e = ``friction_velocity`` h and 1 above. Below the
  threshold friction is a stiff spring that holds the particle (static friction, creeping
  slower than friction_velocity); above it, Coulomb's mu lambda against the sliding.
  lambda is lagged, as IPC lags it: each particle's friction is that of the terrain it pressed
  hardest at the end of the last step, with that step's pressure (state.ContactMemory's
  ``terrain`` and ``friction_damping``: mu lambda), so that within a step friction is the
  gradient of a fixed convex potential. With the pressure of the moment, or of the last
  iteration, a sliding particle could cycle for ever between two block steps, pressed deep
  with strong friction, then thrown out of contact by it (a cube on a 30 degree slope stopped
  dead that way). A particle's first step in contact is therefore without friction.

``delta`` is a tenth of the terrain's contact band (``epsilon``): particles rest inside the band,
where the pass after every step (collision/response/terrain.py) sees them at rest and leaves them.
"""
from .._jit import kernel

OFFSET_OF_BAND = 0.1   # delta as a share of the terrain's contact band


@kernel
def contact_pressure(phi, stiffness, delta):
    """lambda = k (delta - phi), or 0 out of contact (N)."""
    return stiffness * max(delta - phi, 0.0)


@kernel
def contact_share(phi, nx, ny, nz, stiffness, delta, pressed, m0, m1, m2, smoothing):
    """One terrain's share of a particle's block (module doc; as vertex.spring_share gives it)
    at signed distance phi with normal n; pressed: mu lambda, the friction's lagged pressure
    times mu; m: the motion this step relative to the surface, x - x0 - h w; smoothing:
    friction_velocity h (m)."""
    fx = fy = fz = h00 = h01 = h02 = h11 = h12 = h22 = 0.0
    if phi < delta:
        pressure = stiffness * (delta - phi)
        fx, fy, fz = pressure * nx, pressure * ny, pressure * nz
        h00, h01, h02 = stiffness * nx * nx, stiffness * nx * ny, stiffness * nx * nz
        h11, h12, h22 = stiffness * ny * ny, stiffness * ny * nz, stiffness * nz * nz
    if pressed == 0.0:
        return fx, fy, fz, h00, h01, h02, h11, h12, h22
    normal = m0 * nx + m1 * ny + m2 * nz
    t0, t1, t2 = m0 - normal * nx, m1 - normal * ny, m2 - normal * nz
    sliding = (t0 * t0 + t1 * t1 + t2 * t2) ** 0.5
    if sliding < smoothing:   # f1(s) / s
        weight = 2.0 / smoothing - sliding / (smoothing * smoothing)
    else:
        weight = 1.0 / sliding
    hold = pressed * weight
    return (fx - hold * t0, fy - hold * t1, fz - hold * t2,
            h00 + hold * (1.0 - nx * nx), h01 - hold * nx * ny, h02 - hold * nx * nz,
            h11 + hold * (1.0 - ny * ny), h12 - hold * ny * nz, h22 + hold * (1.0 - nz * nz))
