"""The block sparsity pattern of the backward-Euler matrix, fixed when the model is built.

(The integrator stores only the diagonal blocks, ``diagonal_pattern``, and applies the springs'
blocks from their coefficients: ``SolveLayout`` and spring_terms.py; a model with soft
attachments stores their few blocks too, ``coupled_pattern``. The full pattern is the reference
the tests compare it with.)

The matrix has one 3 x 3 block per particle pair that a spring joins (both orders) and one on the
diagonal per particle. The pattern is block compressed sparse rows (BSR): the blocks of row i are
``row_start[i]:row_start[i + 1]``, ``column`` gives their block columns in increasing order. Each
spring knows its four slots, so assembly writes straight into the blocks with no per-step sorting.
"""
from typing import NamedTuple

import numpy as np

from ..spring_runs import run_layout
from ..springs import SpringKind
from .coarse import CoarseSpace, build_coarse_space


class BlockPattern(NamedTuple):
    row_start: np.ndarray       # (P + 1,) int64
    column: np.ndarray          # (B,) int64 block column of every stored block
    diagonal_slot: np.ndarray   # (P,) int64 slot of block (i, i)
    spring_slots: np.ndarray    # (S, 4) int64 slots of blocks (a, a), (b, b), (a, b), (b, a)

    @property
    def block_count(self) -> int:
        return len(self.column)


def build_block_pattern(arrays) -> BlockPattern:
    """The pattern for a model's springs (``ModelArrays``); two springs on one pair share slots."""
    count = len(arrays.inv_mass)
    a = arrays.springs[:, 0].astype(np.int64)
    b = arrays.springs[:, 1].astype(np.int64)
    diagonal = np.arange(count, dtype=np.int64)
    rows = np.concatenate([diagonal, a, b])
    columns = np.concatenate([diagonal, b, a])
    keys = np.unique(rows * count + columns)   # sorted by row, then column
    row_of, column = np.divmod(keys, count)
    row_start = np.searchsorted(row_of, np.arange(count + 1)).astype(np.int64)

    def slot(r, c):
        return np.searchsorted(keys, r * count + c).astype(np.int64)

    spring_slots = np.stack([slot(a, a), slot(b, b), slot(a, b), slot(b, a)], axis=1)
    return BlockPattern(row_start=row_start, column=column.astype(np.int64),
                        diagonal_slot=slot(diagonal, diagonal), spring_slots=spring_slots)


def diagonal_pattern(count: int) -> BlockPattern:
    """The pattern of the diagonal blocks alone, for a matrix whose springs' blocks are not
    stored (spring_terms.py)."""
    diagonal = np.arange(count, dtype=np.int64)
    return BlockPattern(row_start=np.arange(count + 1, dtype=np.int64), column=diagonal,
                        diagonal_slot=diagonal, spring_slots=np.empty((0, 4), np.int64))


def coupled_pattern(count: int, nodes: np.ndarray) -> tuple[BlockPattern, np.ndarray]:
    """The diagonal blocks and those that couple every two particles of a row of ``nodes``
    (A, 4): a soft attachment's stencil (attachments.py), whose blocks are few and are stored.
    Returns the pattern and (A, 4, 4) each row's slots (i, j)."""
    first = np.repeat(nodes, nodes.shape[1], axis=1).reshape(-1)
    second = np.tile(nodes, (1, nodes.shape[1])).reshape(-1)
    diagonal = np.arange(count, dtype=np.int64)
    keys = np.unique(np.concatenate([diagonal * count + diagonal, first * count + second]))
    row_of, column = np.divmod(keys, count)
    row_start = np.searchsorted(row_of, np.arange(count + 1)).astype(np.int64)
    pattern = BlockPattern(row_start=row_start, column=column.astype(np.int64),
                           diagonal_slot=np.searchsorted(keys, diagonal * count + diagonal)
                           .astype(np.int64), spring_slots=np.empty((0, 4), np.int64))
    slots = np.searchsorted(keys, first * count + second).astype(np.int64)
    return pattern, slots.reshape(len(nodes), nodes.shape[1], nodes.shape[1])


class SolveLayout(NamedTuple):
    """What implicit_euler's solve needs of a model, built once: the pattern of the stored
    blocks (the diagonal, and the blocks of the soft attachments), the springs' layout for their
    terms (spring_terms.py), and where each attachment's blocks are."""
    diagonal: BlockPattern
    runs: np.ndarray          # (R, 5) the springs' runs whatever their constants (spring_runs.py)
    run_entries: int          # places in the runs, holes included
    entry_spring: np.ndarray  # (E,) int64 the spring at each place of the runs, -1 at a hole
    loose_springs: np.ndarray  # (L,) int64 the springs in no run
    loose_pairs: np.ndarray   # (L, 2) int64 the particles of each loose spring
    attachment_slots: np.ndarray   # (A, 4, 4) int64: slots of the blocks (i, j) of each
                                   # soft attachment's particles (-1: a hard one, none)
    coarse: CoarseSpace       # the two-level preconditioner's aggregates (coarse.py)


def build_solve_layout(arrays, spring_kind=None) -> SolveLayout:
    """The layout of a model's ``arrays``; ``spring_kind`` (Model.spring_kind) lets the coarse
    space grow its aggregates along the structural and shear springs alone (coarse.py)."""
    count = len(arrays.inv_mass)
    near = (np.ones(len(arrays.springs), bool) if spring_kind is None
            else np.isin(spring_kind, (SpringKind.STRUCTURAL, SpringKind.SHEAR)))
    soft = arrays.attachment_stiffness > 0.0
    slots = np.full((len(soft), 4, 4), -1, np.int64)
    if soft.any():
        diagonal, slots[soft] = coupled_pattern(count, arrays.attachment_nodes[soft])
    else:   # the plain diagonal, whose product cg.search_product takes with the springs'
        diagonal = diagonal_pattern(count)
    # runs of their own: the force loop's runs keep one group each, which a cloth's material
    # cuts short, and a solve's products are most of its time (spring_runs.RunLayout)
    springs = arrays.springs.astype(np.int64).reshape(-1, 2)
    runs = run_layout(springs[:, 0], springs[:, 1])
    return SolveLayout(diagonal=diagonal, runs=runs.runs.astype(np.int64),
                       run_entries=len(runs.entry_spring), entry_spring=runs.entry_spring,
                       loose_springs=runs.loose, loose_pairs=springs[runs.loose].reshape(-1, 2),
                       attachment_slots=slots,
                       coarse=build_coarse_space(count, arrays.springs, near))
