"""The loops over the terms that the integrators call, generated from the registry.

Numba cannot loop over a list of functions, so each loop is generated as source that calls
every term's kernel in turn; for the soft pins and the wind the forces loop reads::

    def add_external_forces(model, x, v, scale, out):
        part_0(model, model.term_tables[0], x, v, scale, out)
        part_2(model, model.term_tables[2], x, v, scale, out)

and is compiled inline into its callers, where it is the same calls as a list written by hand.
"""
import linecache

from numba import njit

from .._jit import FASTMATH

LOOPS = {   # loop name -> (the Term attribute it calls, its arguments)
    "add_external_forces": ("add_forces", "model, x, v, scale, out"),
    "add_step_end_forces": ("add_step_end_forces", "model, x_k, v_k, scale, rhs"),
    "add_external_jacobians": ("add_jacobian",
                               "model, layout, h, first, x_k, v_k, v, blocks, rhs"),
}


def loop_source(name: str, arguments: str, slots) -> str:
    """The loop's source: each term's part with its table after the model."""
    rest = arguments.split(", ", 1)[1]
    lines = [f"def {name}({arguments}):"]
    lines += [f"    part_{slot}(model, model.term_tables[{slot}], {rest})" for slot in slots]
    if not slots:
        lines.append("    return")
    return "\n".join(lines) + "\n"


def build_loop(name: str, terms) -> object:
    """The kernel ``name`` of LOOPS over ``terms``, the terms without its part left out."""
    attribute, arguments = LOOPS[name]
    parts = {term.slot: getattr(term, attribute) for term in terms
             if getattr(term, attribute) is not None}
    source = loop_source(name, arguments, list(parts))
    filename = f"<springsim.terms.dispatch.{name}: generated>"
    # registered with linecache so that tracebacks and Numba's messages can show it
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace = {f"part_{slot}": part for slot, part in parts.items()}
    exec(compile(source, filename, "exec"), namespace)
    return njit(fastmath=FASTMATH, error_model="numpy", inline="always")(namespace[name])
