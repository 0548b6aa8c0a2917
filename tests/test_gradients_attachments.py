"""Gradients through attachments (gradients/attachments.py) against central finite differences
of the forward run, under each integrator with an adjoint: two panels stitched along an edge,
the second thrown sideways and upwards so that the seam works, by a soft stitch (its stiffness
and damping parameters too) and by a hard one (projected after every step, the masses' share
in it included); both also as the panels land on a plane (backward Euler's contact replay
then has the soft stitch's blocks, and holds the hard one after its solves, before the
impacts), and the hard one as a ball is thrown onto the panels (body contact)."""
import pytest

from springsim.attachments import Attachment
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains.plane import Plane
from test_gradients import STEPS, assert_gradients_match

SEAM_Z = 0.5   # the second panel's -z edge, on the first's +z edge
KEYS = ["bodies.0.structural.ks", "bodies.1.shear.kd", "bodies.1.velocity", "gravity",
        "bodies.1.particle_mass"]


def stitched(stiffness=None, damping=0.0):
    """Two 3 x 3 panels 1 m wide, the second's -z edge bound to the first's +z edge, the first
    pinned at one corner, the second moving off at (0.4, 0.8, 0.3) m/s."""
    from springsim.bodies.pins import Region
    springs = {kind: SpringParameters(300.0, 0.4) for kind in ("structural", "shear", "bend")}
    first = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned=[0],
                  self_collision=False, **springs)
    second = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned="none",
                   self_collision=False, position=(0.0, 0.0, 1.0), velocity=(0.4, 0.8, 0.3),
                   particle_mass=0.8, **springs)
    seam = Region(min=(-1.0, -0.1, SEAM_Z - 0.01), max=(1.0, 0.1, SEAM_Z + 0.01))
    stitch = Attachment(body=1, to=0, region=seam, stiffness=stiffness, damping=damping)
    return Scene(bodies=[first, second], attachments=[stitch], terrains=[])


def landing(stiffness=None):
    """The stitched panels 1 cm above a plane, thrown down onto it at 2 m/s, the second
    sideways too (the seam works while they land)."""
    scene = stitched(stiffness=stiffness, damping=0.5 if stiffness else 0.0)
    scene.bodies[0].pinned = "none"
    scene.bodies[0].velocity = (0.0, -2.0, 0.0)
    scene.bodies[1].velocity = (1.5, -2.0, 1.0)
    scene.terrains = [Plane(point=(0.0, -0.01, 0.0), friction=0.4, restitution=0.3)]
    return scene


def hard_with_ball():
    """The hard-stitched panels, a ball 2 mm above the second thrown down onto it as it rises:
    body contact in the steps that hold the stitch (under implicit_euler, the bodies' replay
    holds it before the post-step pass)."""
    from springsim.bodies.balls import Ball, Balls
    scene = stitched()
    ball = Ball(position=(0.1, 0.202, 1.0), velocity=(0.2, -1.0, 0.0), radius=0.2, mass=1.0)
    scene.bodies.append(Balls(balls=[ball], particle_restitution=0.3, particle_friction=0.4))
    return scene


SOFT_KEYS = ["attachments.0.stiffness", "attachments.0.damping"]
SCENES = {"soft": (lambda: stitched(stiffness=60.0, damping=0.5), KEYS + SOFT_KEYS),
          "hard": (stitched, KEYS),
          "soft-landing": (lambda: landing(stiffness=60.0),
                           ["bodies.1.velocity", "gravity", "terrains.0.friction"] + SOFT_KEYS),
          "hard-landing": (landing, ["bodies.1.velocity", "gravity", "terrains.0.friction",
                                     "bodies.1.particle_mass"]),
          "hard-ball": (hard_with_ball, ["bodies.1.velocity", "gravity", "bodies.1.particle_mass",
                                         "bodies.2.balls.0.velocity"])}


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", list(STEPS))
def test_attachment_gradients_match_finite_differences(integrator, case):
    scene_of, names = SCENES[case]
    assert_gradients_match(scene_of, integrator, names)


def test_fit_recovers_a_stitch(tmp_path, capsys):
    """`springsim fit --fit attachments.0.stiffness --fit attachments.0.damping`: a take of
    the soft-stitched panels (60 N/m, 0.5 N s/m), fitted from 25 N/m, gives the stitch back."""
    import json

    from springsim.cli import main
    from springsim.scenefile import scene_to_toml

    scene_file = tmp_path / "stitched.toml"
    scene_file.write_text(scene_to_toml(stitched(stiffness=60.0, damping=0.5)))
    options = ["--integrator", "implicit_euler", "--dt", "0.01"]
    take = tmp_path / "take.npz"
    assert main(["run", str(scene_file), *options, "--duration", "0.5", "--out", str(take),
                 "--quiet"]) == 0
    assert main(["fit", str(scene_file), *options, "--observed", str(take), "--fit",
                 "attachments.0.stiffness", "--fit", "attachments.0.damping", "--set",
                 "attachments.0.stiffness=25", "--out", str(tmp_path / "fitted.toml")]) == 0
    fitted = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["fitted"]
    assert fitted["attachments.0.stiffness"] == pytest.approx(60.0, rel=1e-4)
    assert fitted["attachments.0.damping"] == pytest.approx(0.5, rel=1e-3)
