"""Collision handling, laid out as the pipeline runs. Every integrator's step goes through it.

    shapes/        what can touch: particles (balls with radii, surface points), surface
                   triangles and edges, gathered once when the model is built; terrains are
                   their own package (springsim.terrains), reached through response/terrain.py
        |
    broad_phase/   candidates without testing every pair: grid.py, the uniform grid (its cell
                   arithmetic and counting sort; particles as points or shapes as boxes);
                   balls.py, (ball, particle) pairs; surfaces.py, (point, triangle) and
                   (edge, edge) pairs within a reach
        |
    pair_lists/    surface pairs kept between steps (a Verlet list: keeping.py) and the proofs
                   that let a list be kept or skip a search (rigid_pieces.py, unfolded_sheet.py);
                   the implicit solve's own lists (solve_pairs.py: pairs of two bodies within a
                   step's reach; own_pairs.py: a self-colliding body's pairs in contact)
        |
    narrow_phase/  one stencil per touching pair: four particles, signed weights c summing to
                   zero and a normal, from the one builder of stencils.py. after_step.py, at the
                   end of a step (impulse contacts); solve.py, at a Newton estimate (penalty
                   contacts of the solve)
        |
    contact_sets/  the stencils gathered into one named set: ImpulseContacts (after the step),
                   SolveContacts (inside backward Euler's solve)
        |
    ccd/           continuous collision check: did a step carry a surface through another?
                   (backward Euler then takes the step again in halves)
        |
    response/      terrain.py, terrain contact forces and impacts; impulses.py and overlap.py,
                   the Jacobi impulse passes with mass splitting and the overlap correction;
                   penalty.py, contacts as one-sided springs of the implicit solve;
                   solve_friction.py, Coulomb friction of those springs
    (the closest points and distances every stage measures with are ../geometry/, below the
    terrains and attachments that use them too)

pipeline.py runs the stages after every integrator's update (``resolve_contacts``):
keep or renew the pair list, find the touching stencils, respond. Backward Euler also calls the
stages inside its solve (integrators/implicit_euler.py).

Every contact, whatever its shape, is a stencil: d = sum_i c_i x_i runs from one side of the
contact to the other, and an impulse or a force along n acts on particle i with weight c_i, so
contact conserves momentum as the springs do.
"""
