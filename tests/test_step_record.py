"""Backward Euler's step record (implicit/step_record.py): what the forward decided, kept for the
gradient, and read by its replay (gradients/implicit_replay.py) instead of decided again.
Oracles: the record against the state the step leaves (its contacts, their terrains, the
Newton iterations asked for); a record with too little room grown and the step taken again bit
for bit; the replay following a decision changed in the record (a holding contact told it slid
takes Coulomb / sliding, not Coulomb / SLIP_SPEED), which a replay deciding from its own
numbers would not."""
import numpy as np
import pytest

import springsim
from springsim.gradients.tape import Kept, recorded_step, recording
from springsim.implicit.constraints import (CONTACT, GROWN, HOLDING, RELEASED, SLIDING,
                                            SLIP_SPEED, UNCHANGED)
from springsim.implicit.step_record import new_record, no_record


def landing(newton_iterations=1):
    """The default cube under implicit_euler at 1/60 s, 20 steps before it lands on the plane
    (it reaches the floor at about 1.3 s and rests there)."""
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"),
                                      integrator="implicit_euler", dt=1 / 60, threads=1,
                                      newton_iterations=newton_iterations)
    simulation.step(60)
    return simulation


def recorded_steps(simulation, count):
    """``count`` steps recorded as the gradient's tape records them: [Kept] of each start."""
    from springsim.gradients.tape import snapshot

    states = []
    with recording(simulation):
        for _ in range(count):
            states.append(snapshot(simulation.state, True))
            recorded_step(simulation, states)
    return states


def test_a_run_without_a_record_notes_nothing_and_moves_as_with_one():
    plain, kept = landing(), landing()
    assert plain.integrator.record is None
    plain.step(30)
    states = recorded_steps(kept, 30)
    assert all(isinstance(state, Kept) and state.record is not None for state in states)
    assert kept.integrator.record is None   # switched off again after the recording
    assert plain.positions.tobytes() == kept.positions.tobytes()
    assert plain.velocities.tobytes() == kept.velocities.tobytes()
    assert no_record().counts.shape == (0,)


@pytest.mark.parametrize("newton_iterations", [1, 2])
def test_the_record_says_what_the_step_decided(newton_iterations):
    """Over the landing: each record's start contacts are the contacts of the state the step
    starts from once found (the kind the next step's memory carries), every Newton iteration
    asked for is a try, the passes add up, and the cube's landing makes contacts (GROWN or at
    a step's start) that the state then holds."""
    simulation = landing(newton_iterations)
    states = recorded_steps(simulation, 40)
    made = 0
    for before, after in zip(states, states[1:]):
        record = before.record
        tries = record.tries
        assert len(tries) == newton_iterations   # no fold closes: no try taken again
        assert (tries[:, 2] == 0).all()
        assert 1 <= tries[:, 1].min() and (tries[:, 0] <= 4).all()
        # a cap row for the first iteration, then one row per update pass
        assert len(record.rows) == 1 + int(tries[:, 0].sum())
        decided = record.rows[1:]
        made += int(np.sum(record.kind == CONTACT)) + int(np.sum(decided >= GROWN))
        # what the step leaves: contacts the record started or grew, less those it released
        final = record.kind == CONTACT
        for row in decided:
            final = (final | (row >= GROWN)) & (row != RELEASED)
        assert np.array_equal(final, after.memory.kind == CONTACT)
        assert set(np.unique(decided)) <= {UNCHANGED, SLIDING, HOLDING, RELEASED, GROWN}
    assert made > 0


def test_a_record_with_too_little_room_is_grown_and_the_step_taken_again():
    plain, kept = landing(), landing()
    plain.step(40)
    states = []
    from springsim.gradients.tape import snapshot

    with recording(kept):
        kept.integrator.record = new_record(kept.model.particle_count, 1, 1)
        for _ in range(40):
            states.append(snapshot(kept.state, True))
            recorded_step(kept, states)
    assert plain.positions.tobytes() == kept.positions.tobytes()
    assert plain.velocities.tobytes() == kept.velocities.tobytes()
    assert all(len(state.record.rows) == state.record.counts[0] for state in states)
    assert max(len(state.record.rows) for state in states) > 1


def test_the_replay_follows_the_record_not_its_own_numbers():
    """A step of the cube resting on the plane, its contacts held by friction: replayed from
    its record, then from the record with one contact that held in the step's last pass marked
    released there. The first keeps its damper Coulomb / SLIP_SPEED; the second lets it go (no
    damper, free at the step's end) though its terrain pushes on it: the replay does what the
    record says, not what its own numbers would choose."""
    from springsim.gradients.clock import STEP_START, at_time
    from springsim.gradients.implicit_replay import replay
    from springsim.gradients.physics import Physical
    from springsim.gradients.pins import aim, place
    from springsim.implicit.constraints import FREE

    simulation = landing()
    simulation.step(60)   # at rest on the floor
    began = simulation.state.time
    start = recorded_steps(simulation, 1)[0]
    physical = Physical.of(simulation.model)
    h = simulation.dt
    physical.clock[STEP_START] = began   # as the backward pass sets it (tape.backward)
    at_time(physical, 0.0)
    x, v = place(physical, start.x, start.v)
    at_time(physical, h)
    v = aim(physical, x, v, h)
    # the step's last pass: the dampers it chose are the ones the step leaves
    last = len(start.record.rows) - 1
    held = np.nonzero(start.record.rows[last] == HOLDING)[0]
    assert len(held) > 0
    i = held[0]

    def last_update(replayed):
        return [step for step in replayed.iterations[-1].steps if hasattr(step, "case")][-1]

    _, _, c_held, replayed = replay(physical, h, x, v, start.memory, start.record)
    update = last_update(replayed)
    k = list(update.index).index(i)
    assert update.case[k] == HOLDING and update.impulse[k] > 0.0   # the terrain pushes
    assert c_held[i] == pytest.approx(physical.friction[0] * update.impulse[k] / SLIP_SPEED,
                                      rel=1e-12)
    assert replayed.constraints.kind[i] == CONTACT
    rows = start.record.rows.copy()
    rows[last, i] = RELEASED
    _, _, c_released, replayed = replay(physical, h, x, v, start.memory,
                                        start.record._replace(rows=rows))
    update = last_update(replayed)
    assert i in update.released and i not in update.index
    assert c_released[i] == 0.0
    assert replayed.constraints.kind[i] == FREE
