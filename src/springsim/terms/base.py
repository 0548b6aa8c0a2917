"""What a term is, and the registry the integrators and adjoints loop over.

A term is one force on the particles (a soft pin, a soft attachment, the wind, ...) that every
integrator applies the same way. Its class gives the forward kernels, each taking the model, the
term's own table of parameters (``table``: what ``pack`` built, ``model.term_tables[slot]``) and
adding into an output; a part a term lacks is None and is left out of the loop:

- ``add_forces(model, table, x, v, scale, out)``: out[i] += scale_i F_i(x, v), ``scale`` per particle
  (the inverse masses: the explicit methods' accelerations) or one number for all (the step h:
  backward Euler's impulses);
- ``add_step_end_forces(model, table, x_k, v_k, scale, rhs)``: backward Euler's h F at the Newton
  estimate, added into the right-hand side with the springs' (a term whose force comes with its
  Jacobian in one pass adds it in ``add_jacobian`` instead, and leaves this None);
- ``add_jacobian(model, table, layout, h, first, x_k, v_k, v, blocks, rhs)``: its share of the system
  matrix A = M - h dF/dv - h^2 dF/dx at the estimate (into ``blocks``, the slots of
  implicit/pattern.py's ``layout``), and in the ``first`` iteration its h^2 dF/dx v in ``rhs``;
- ``adjoint``: "module:Class" of its adjoint term (gradients/terms.py), which the gradients
  import when a run is differentiated;
- ``used(arrays)``: whether a model has any of it (the plain kernels leave the terms out:
  plain.py);
- ``order``: where it stands in the loops (the order its forces are summed in);
- ``scene_type`` and ``settings``: the ``type`` name and dataclass of the tables a scene file's
  ``[[forces]]`` list holds for it (none for the forces that have scene keys of their own), and
  ``pack(scene, built, offsets)``: its table (a NamedTuple of arrays, the same types whether or
  not the scene uses it, so that one compiled kernel serves every scene).

A new term is one new file in this package that defines such a class and calls ``register``:
the package imports every module in it, and dispatch.py generates the loops.
"""

TERMS: list = []         # term classes, in the order the loops call them
FORCE_TYPES: dict = {}   # [[forces]] ``type`` name -> settings dataclass
_registered: list = []   # (order, cls) as the term files are imported


class Term:
    """The parts every term may give (module doc); None: it has none."""

    name = ""
    add_forces = None
    add_step_end_forces = None
    add_jacobian = None
    adjoint = ""
    order = 0
    scene_type = ""
    settings = None
    slot = -1   # its place in TERMS and model.term_tables (registered_terms)

    @classmethod
    def pack(cls, scene, built, offsets) -> tuple:
        """Its table; the forces with model arrays of their own have none."""
        return ()

    @classmethod
    def used(cls, arrays) -> bool:
        """Whether the model (its ModelArrays) has any of this force: the plain kernels,
        compiled without the terms, serve only models that use none (plain.py). By default,
        whether its table has a row; the forces with model arrays of their own say it."""
        return any(len(column) > 0 for column in arrays.term_tables[cls.slot])


def register(cls):
    """Add a term (module doc); returns ``cls``, so that it can decorate the class."""
    _registered.append((cls.order, cls))
    if cls.scene_type:
        FORCE_TYPES[cls.scene_type] = cls.settings
    return cls


def registered_terms() -> list:
    """Fill TERMS by ``order`` once every term file is imported."""
    TERMS[:] = [cls for _, cls in sorted(_registered, key=lambda entry: entry[0])]
    for slot, cls in enumerate(TERMS):
        cls.slot = slot
    return TERMS


def scene_forces(scene, settings) -> list:
    """The entries of ``scene.forces`` of the dataclass ``settings``, with their numbers."""
    return [(number, force) for number, force in enumerate(scene.forces)
            if type(force) is settings]
