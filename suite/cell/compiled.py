"""A cell's compiled kernels, loaded: what the driver objects call.

:func:`compile_cell` assembles (or loads) the cell's kernel modules and its problem's module
(:func:`gnibench.methods.assembly.assemble`) and builds the run-time parameters ``par`` (the
problem's model parameters, then each modifier's numbers: H0 and gains, [B] (2.5)-(2.6), (2.10),
then the method's runtime options and data). A cell has one module per output of its driver kind
(:meth:`CompiledCell.driver`); ``kernel`` is the one of its plain samples, which also holds the
field, the step and the continuous extension. numba compiles (or loads from its disk cache) each
function on its first call: the driver objects (:func:`gnibench.suite.cell.drivers.ready_cell`)
warm up the driver a cell will use by one step, so that this is timed apart from the
integration.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from types import ModuleType

import numpy as np
from gnibench.methods.assembly import assemble, assemble_problem, kernel_text
from gnibench.methods.assembly.bindings import DRIVER_NAMES
from gnibench.methods.assembly.loading import cache_misses, compiled_before, key
from gnibench.suite.foundation.params import Bound


@dataclass
class CompiledCell:
    """The compiled parts of one cell and the numbers they run with.

    ``kernel`` is the cell's module of plain samples (field with modifiers, method step, its
    driver, dense output); :meth:`driver` gives a driver by name from the module of its output;
    ``problem_kernel`` is the problem's own (integrals, ``eval_invariants``, section functions).
    """

    kernel: ModuleType
    problem_kernel: ModuleType
    problem: Bound
    method: object
    integral_names: tuple[str, ...]
    problem_par: np.ndarray
    par: np.ndarray
    y0: tuple[float, ...]
    H0: tuple[float, ...]
    compile_seconds: float
    warm: set = field(default_factory=set)     # drivers already loaded or compiled and run once
    modules: dict = field(default_factory=dict)  # output -> its module

    def module(self, output: str) -> ModuleType:
        """The cell's module for ``output`` (assembled on first use)."""
        if output not in self.modules:
            self.modules[output] = (self.kernel if output == "samples"
                                    else assemble(self.problem, self.method, output))
        return self.modules[output]

    def driver(self, name: str):
        """The compiled driver Python knows as ``name`` (``integrate``, ``integrate_grid``,
        ``integrate_dense``, ...: methods/assembly/bindings.py ``DRIVER_NAMES``)."""
        from gnibench.methods.assembly.bindings import DRIVERS

        kind, output = DRIVER_NAMES[name]
        return getattr(self.module(output), DRIVERS[kind].loop.__name__)

    def loaded(self) -> tuple[ModuleType, ...]:
        """The modules loaded for this cell so far, and the problem's."""
        return (*{id(m): m for m in (self.kernel, *self.modules.values())}.values(),
                self.problem_kernel)

    @property
    def cache_misses(self) -> int:
        """Functions compiled in this process instead of loaded from numba's disk cache."""
        return sum(cache_misses(module) for module in self.loaded())


@dataclass
class ProblemKernel:
    """A problem's compiled module and what evaluating its integrals needs."""

    kernel: ModuleType
    integral_names: tuple[str, ...]
    par: np.ndarray

    def integrals(self, y: np.ndarray) -> np.ndarray:
        """I_k at every row of y, shape (rows, q)."""
        y = np.ascontiguousarray(y, dtype=np.float64)
        out = np.empty((len(y), len(self.integral_names)))
        if len(y) and self.integral_names:
            self.kernel.eval_invariants(y, self.par, len(y), out)
        return out

    def at(self, y) -> tuple[float, ...]:
        """I_k at one state (by ``eval_invariants``, the function that evaluates them at the
        samples: ``invariants`` called from Python would be one more function to compile)."""
        if not self.integral_names:
            return ()
        return tuple(float(v) for v in self.integrals(np.array([y], dtype=np.float64))[0])


def problem_kernel(problem: Bound) -> ProblemKernel:
    from gnibench.problems.codegen import problem_meta

    kernel = assemble_problem(problem)
    par = np.array(problem.record.par(problem.values), dtype=np.float64)
    return ProblemKernel(kernel, tuple(problem_meta(problem.record)["integrals"]), par)


_cells: dict[tuple[str, str], CompiledCell] = {}


def forget_damaged(problem: Bound, method) -> bool:
    """After loading or warming up a cell failed: forget its generated modules and remove their
    numba cache files (:func:`gnibench.methods.assembly.loading.forget`), so that the next
    :func:`compile_cell` compiles them afresh. True if there were cache files to blame; False
    means the failure did not come from the cache."""
    from gnibench.methods.assembly.loading import forget

    modules = {assemble(problem, method, "samples"), assemble_problem(problem)}
    for k, cell in list(_cells.items()):
        if k[:2] == (problem.text(), method.text()):
            modules.update(cell.loaded())
    for k, cell in list(_cells.items()):
        if modules & set(cell.loaded()):
            del _cells[k]
    return forget(*modules)


def compile_cell(problem: Bound, method) -> CompiledCell:
    """Load the cell's kernels and build ``par``. A cell loaded once in this process is kept (keyed
    by its canonical specs, which fix its module text and ``par``, and by the definitions of user
records, which an edited file changes under the same specs): a worker that runs many cells of
    one kernel loads it once; ``warm`` lists its drivers already run once. ``compile_seconds`` is
    what this call took."""
    key = (problem.text(), method.text(), getattr(problem.record, "definition", None),
           getattr(getattr(method, "base", method).record, "definition", None))
    t0 = time.perf_counter()
    if key not in _cells:
        _cells[key] = _compile(problem, method)
    return replace(_cells[key], compile_seconds=time.perf_counter() - t0)


def _compile(problem: Bound, method) -> CompiledCell:
    rec = problem.record
    y0 = tuple(rec.y0(problem.values))
    kernel = assemble(problem, method, "samples")
    pk = problem_kernel(problem)
    h0_all = pk.at(y0)
    extra = []
    for m in method.modifiers:
        idx = [pk.integral_names.index(x) for x in m.values["on"]]
        extra.extend(m.record.runtime(m.values, [h0_all[k] for k in idx]))
    base = method.base      # then the method's runtime options (Method.runtime), in that order,
    extra.extend(float(base.values[name]) for name in base.record.runtime)
    extra.extend(float(x) for x in base.record.runtime_data)   # and its Method.runtime_data
    par = np.concatenate([pk.par, np.array(extra, dtype=np.float64)])
    return CompiledCell(kernel, pk.kernel, problem, method, pk.integral_names, pk.par, par, y0,
                        h0_all, 0.0)


def dense_output_refusal(problem: Bound, method) -> str:
    """Why the cell's accepted steps are not the endpoints of its method's continuous extension
    (methods/dense_output.py), or "" when dense output applies."""
    base = method.base
    if getattr(base.record.data, "dense", None) is None:
        return f"{base.id} has no continuous extension (dense output: dopri5, dop853)"
    if not base.values.get("adaptive"):
        return f"{base.id} runs at fixed step (adaptive=false)"
    steps = [m.record.id for m in method.modifiers if m.record.kind == "step"]
    if steps:
        return f"+{steps[0]} moves each accepted point off the continuous extension's endpoint"
    if problem.record.post_step is not None:
        return (f"{problem.id} maps each accepted point by its identification (post_step), off the "
                f"continuous extension's endpoint")
    return ""


def kernel_key(problem: Bound, method) -> str:
    """What a cell compiles: the hash of its kernel module's text (the module of its plain samples;
    of the transformed system for a transformed problem; a part sympy takes seconds to make stands
    as the digest of what it is made from), or the external engine and problem."""
    return kernel_plan(problem, method)[0]


def kernel_plan(problem: Bound, method) -> tuple[str, int]:
    """The kernel key (:func:`kernel_key`) and a guess of what compiling it costs: the length of
    the module's text when it is not in the kernel cache yet (a text with a keyed part never is
    found there: it counts as not compiled), else 0; 0 for an engine."""
    if method.kind != "compiled":
        return f"engine:{method.base.record.engine}:{problem.id}", 0
    target = problem.record.transformed(problem.values) or problem
    text = kernel_text(target, method)
    return key(text), 0 if compiled_before(text) else len(text)
