"""The broad phase finds exactly the overlapping pairs, in one order, by grid and by brute force."""
import numpy as np
import pytest

import springsim
from springsim.collision.broad_phase.balls import (brute_force_pairs, find_contacts,
                                                   first_capacity, grid_pairs, search_size)


def numpy_pairs(x, radius, balls):
    """The contact set straight from its definition: (ball a, particle b) with
    |x_a - x_b| < r_a + r_b, b != a, and each ball-ball pair once, from the lower ball."""
    is_ball = radius > 0
    distance = np.linalg.norm(x[balls][:, None, :] - x[None, :, :], axis=2)
    touching = distance < radius[balls][:, None] + radius[None, :]
    pairs = [(a, b) for row, a in enumerate(balls) for b in np.flatnonzero(touching[row])
             if b != a and (not is_ball[b] or b > a)]
    return np.array(pairs, np.int64).reshape(-1, 2)


def random_scene(seed, points, balls, spread=3.0):
    rng = np.random.default_rng(seed)
    count = points + balls
    x = rng.uniform(-spread, spread, (count, 3))
    radius = np.zeros(count)
    ball_index = np.sort(rng.choice(count, balls, replace=False))
    radius[ball_index] = rng.uniform(0.05, 0.8, balls)
    return x, radius, ball_index


def ball_slot_of(radius):
    slot = np.full(len(radius), -1, np.int64)
    slot[radius > 0] = np.arange(np.count_nonzero(radius > 0))
    return slot


def both_methods(x, radius, balls):
    slot = ball_slot_of(radius)
    return brute_force_pairs(x, radius, balls, slot), grid_pairs(x, radius, balls, slot)


@pytest.mark.parametrize("seed", range(8))
def test_grid_finds_exactly_the_brute_force_pairs_on_random_scenes(seed):
    x, radius, balls = random_scene(seed, points=400 + 100 * seed, balls=5 + 7 * seed)
    brute, grid = both_methods(x, radius, balls)
    expected = numpy_pairs(x, radius, balls)
    assert len(expected) > 0
    np.testing.assert_array_equal(brute, expected)
    np.testing.assert_array_equal(grid, expected)


def test_crowded_scene_overflows_the_first_buffer_and_still_matches():
    # every ball touches hundreds of points: far more pairs than the initial buffer holds
    x, radius, balls = random_scene(11, points=2000, balls=30, spread=0.5)
    brute, grid = both_methods(x, radius, balls)
    assert len(brute) > first_capacity(balls)
    np.testing.assert_array_equal(grid, brute)
    np.testing.assert_array_equal(brute, numpy_pairs(x, radius, balls))


def test_degenerate_positions_far_coincident_and_nan():
    x, radius, balls = random_scene(3, points=300, balls=12)
    far, centred, diverged = np.setdiff1d(np.arange(len(x)), balls)[:3]
    x[far] = (1e9, -1e9, 3e8)         # one particle far away: the grid coarsens, stays exact
    x[centred] = x[balls[0]]          # a point at a ball's very centre
    x[balls[2]] = x[balls[1]]         # two concentric balls
    x[diverged] = np.nan              # a diverged particle touches nothing
    brute, grid = both_methods(x, radius, balls)
    np.testing.assert_array_equal(grid, brute)
    pairs = set(map(tuple, brute))
    assert (balls[0], centred) in pairs and (balls[1], balls[2]) in pairs
    assert diverged not in brute[:, 1] and far not in brute[:, 1]


def test_very_different_ball_sizes():
    x, radius, balls = random_scene(5, points=500, balls=20)
    radius[balls[::2]] = 0.01
    radius[balls[1::2]] = 1.5
    brute, grid = both_methods(x, radius, balls)
    np.testing.assert_array_equal(grid, brute)
    np.testing.assert_array_equal(brute, numpy_pairs(x, radius, balls))


def test_grid_on_the_large_cloth_scene_searches_a_small_share_of_all_pairs():
    sim = springsim.Simulation(springsim.load_scene("cloth-balls-100"))
    model = sim.model.arrays
    x = sim.positions.copy()
    x[model.balls, 1] = 0.3  # lower the balls into the cloth so that every ball has contacts
    slot = model.ball_slot
    grid = grid_pairs(x, model.radius, model.balls, slot)
    np.testing.assert_array_equal(grid, brute_force_pairs(x, model.radius, model.balls, slot))
    np.testing.assert_array_equal(find_contacts(x, model.radius, model.balls, slot), grid)
    assert len(grid) > 100
    every_pair = len(model.balls) * len(x)
    assert search_size(x, model.radius, model.balls, slot) < 0.05 * every_pair
