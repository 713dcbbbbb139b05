"""The driver of a kernel module: the compiled loop Python calls, and the parts its output adds.

A cell runs one driver kind, fixed step or adaptive (the method option ``adaptive``), with one
output (:data:`gnibench.methods.assembly.bindings.DRIVERS`): samples every ``every`` steps, the
time grid t_k = k dt_out by partial steps, the grid by dense output, or the crossings of a
Poincaré section (located by Hénon's trick or on the continuous extension). A module holds one
driver: its loop template (templates/fixed.py or templates/adaptive.py) copied under its own
name, the loop's flags as module constants (numba drops the branches of the other outputs, so a
driver compiles only its own code), and the parts the output needs:

* ``grid``: ``partial_sample``, ``grid_sample`` (templates/events.py) and ``grid_rows``
  (templates/sampling.py) over the family's ``partial_step`` (the fixed step's own for the fixed
  kind, templates/fixed.py; an adaptive family binds its own);
* ``dense_grid``: ``grid_rows`` by the continuous extension, and ``dense_root`` with the grid time
  as its root (``root_value``, ``root_slope``);
* ``section`` and ``dense_section``: methods/assembly/sections.py.
"""
from __future__ import annotations

from gnibench.methods.assembly.bindings import DRIVERS, FLAGS
from gnibench.methods.assembly.sections import dense_section_parts, section_parts
from gnibench.methods.assembly.source import ENTRY, INLINE, INTERNAL, constants, copy
from gnibench.methods.assembly.templates import events, fixed, sampling


def grid_parts() -> str:
    """Samples on the time grid by partial steps of the method (``partial_step``)."""
    return (copy(events.partial_sample) + copy(events.grid_sample)
            + copy(sampling.grid_rows, INLINE))


def dense_grid_parts() -> str:
    """Samples on the time grid by the continuous extension: the grid time as the root."""
    return ("\n" + INLINE + "\ndef root_value(u, par, tc, tk):\n    return u[tc] - tk\n"
            "\n" + INLINE + "\ndef root_slope(u, du, par, tc):\n    return du[tc]\n"
            + copy(events.dense_root) + copy(sampling.grid_rows, INLINE))


def write_driver(kind: str, output: str, n: int, locator_from: str = "") -> str:
    """The driver of ``kind`` for ``output``: flags, parts, and the loop (an ``@entry``)."""
    driver = DRIVERS[kind]
    out = driver.outputs[output]
    text = constants(**{flag: flag in out.flags for flag in FLAGS})
    for part in out.parts:
        if part == "fixed_partial_step":
            text += copy(fixed.partial_step, INTERNAL)
        elif part == "grid":
            text += grid_parts()
        elif part == "dense_grid":
            text += dense_grid_parts()
        elif part == "section":
            text += section_parts(n, locator_from)
        elif part == "dense_section":
            text += dense_section_parts(n)
        else:
            raise ValueError(f"unknown part {part!r} of output {output!r}")
    return text + copy(driver.loop, ENTRY)
