"""Assemble, cache and load the compiled module of one cell (problem x modifiers x method).

numba's ``cache=True`` cannot cache a jitted function that receives another jitted function as an
argument, so every cell gets its own generated module in which the problem's functions, the
modifier terms, the method's step and the driver are plain ``@njit`` globals calling each other by
name (the functions Python calls are cached by numba, :data:`PYTHON_ENTRIES`). The module text is
keyed by its own hash; its file and numba's cache files live in ``<cache>/kernels``, so a second
run in a new process loads machine code instead of compiling.
When the file is written, the small functions are written into their callers
(:mod:`gnibench.suite.foundation.inline`, :data:`INLINED`): numba then compiles a handful of
functions per cell instead of 20 to 50 (kepler-2d dopri5: 33 compilations, 2.0 s of CPU, became 8,
1.2 s).

Every function is compiled with ``error_model='numpy'``: with numba's default ('python') each float
division checks for a zero divisor and may raise, so LLVM can neither drop a division whose result
is unused nor schedule it freely (Störmer-Verlet's explicit blocks evaluate f twice and use half
of each; measured 1.5x slower than C on kepler-2d with the check, 0.95x without). Results are
bit-identical; a division by zero yields inf/nan (a ``nonfinite`` or ``newton_failed`` status) instead
of raising ZeroDivisionError out of the kernel.
"""
from __future__ import annotations

import contextlib
import functools
import gc
import hashlib
import importlib.util
import re
import sys
import time
from pathlib import Path
from typing import Any

from gnibench.suite.foundation import datastack, numba_passes
from gnibench.suite.foundation.cache import (
    cache_dir,
    discard,
    discard_numba_files,
    numba_cache_path,
    record_numba_files,
    verify_numba_files,
    warn,
    write_atomic,
)
from gnibench.suite.foundation.files import NotRegularFile, read_regular
from gnibench.suite.foundation.inline import inline_source
from gnibench.suite.foundation.numba_typing import install as install_typing_memo
from gnibench.suite.foundation.status import kernel_constants
from gnibench.suite.foundation.templates import Context, store_source, template, tuple_helpers


def field_source(ctx: Context, modifiers, offsets) -> str:
    """f and fjac: the base field plus each modifier's term ([B] (2.5), (2.10))."""
    parts = []
    terms = []
    jacs = []
    projections = []
    for k, (mod, off) in enumerate(zip(modifiers, offsets)):
        parts.append(mod.record.generate(ctx, mod.values, k, off))
        if mod.record.kind == "step":
            projections.append(k)
            continue
        terms.append(f"mod{k}_term(y, par)")
        jacs.append(f"    mod{k}_jac(y, par, J)")
    n = ctx.n
    if terms:
        sums = ", ".join(f"z[{i}] + " + " + ".join(f"m{k}[{i}]" for k in range(len(terms)))
                         for i in range(n))
        binds = "\n".join(f"    m{k} = {t}" for k, t in enumerate(terms))
        body = f"    z = base_f(y, par)\n{binds}\n    return ({sums}{',' if n == 1 else ''})"
    else:
        body = "    return base_f(y, par)"
    parts.append(f"\n@njit(cache=True)\ndef f(y, par):\n{body}\n")
    parts.append("\n@njit(cache=True)\ndef fjac(y, par, J):\n    base_jac(y, par, J)\n"
                 + "\n".join(jacs) + "\n")
    # step modifiers (projection) map each accepted step, in the order given
    chain = "".join(f"    y, s = proj{k}(y, par)\n    if s != STATUS_OK:\n        return y, s\n"
                    for k in projections)
    deco = "@njit(cache=True)" if chain else "@njit(cache=True, inline='always')"
    parts.append(f"\n{deco}\ndef project(y, par):\n{chain}    return y, STATUS_OK\n")
    return "".join(parts)


#: The functions of a generated module that Python calls (the drivers of
#: suite/cell/drivers.py, the problem's functions, the integrals at the samples, the section scans,
#: dense output in the tests), and the prefixes of the problem's integrals and gradients. Every
#: other function is called only from compiled code and is compiled without the two wrappers numba
#: makes for each function (``no_cpython_wrapper``, ``no_cfunc_wrapper``): the CPython wrapper
#: unboxes the tuple arguments and boxes the result, and it was ~40 % of the compile time of a cell
#: (measured: kepler-2d with dopri5, implicit-midpoint, henon-heiles rk4+observer, 11.1 s -> 6.9 s
#: of CPU). The compiled code of the drivers is unchanged (the callees are inlined into them).
#: Such a function called from Python raises TypeError instead of calling a missing entry point.
#: It is not cached by numba either: its machine code is linked into each caller's and saved in the
#: caller's cache files, and a caller loaded from the cache never compiles its callees. Saving it
#: cost 5 % of a cell's cold compile for files no run loads (10 cells of 7 problems and 8 methods:
#: 10.0 s -> 9.5 s of CPU, three runs each); a process that compiles a second driver of the same
#: cell compiles its callees once more.
PYTHON_ENTRIES = ("integrate", "integrate_grid", "integrate_section", "integrate_adaptive",
                  "adaptive_grid", "integrate_dense", "adaptive_section", "adaptive_section_dense",
                  "eval_invariants", "invariants", "section_values", "henon_all", "base_f",
                  "base_jac", "f", "fjac", "dense_coeffs", "dense_eval", "dense_slope")
PYTHON_PREFIXES = ("integral_", "grad_")


def _header(n: int, newton_maxit: int = 50, compensated: bool = False) -> str:
    from gnibench.methods.events import event_constants
    from gnibench.methods.kernels.slots import slot_constants

    return ("# generated by gnibench (suite/cell/codegen.py); do not edit\n"
            "import math\n\nimport numpy as np\nfrom numba import njit as _njit\n"
            "from numba.core.registry import CPUDispatcher\n\n"
            f"PYTHON_ENTRIES = {PYTHON_ENTRIES!r}\n\n\n"
            "class Internal(CPUDispatcher):\n"
            "    def __call__(self, *args, **kws):\n"
            "        raise TypeError(f'{self.py_func.__name__} is called only from compiled code')\n"
            "\n\n"
            "def njit(**kw):  # error_model='numpy': x/0 gives inf/nan instead of raising\n"
            "    def jit(fn):\n"
            f"        if fn.__name__ in PYTHON_ENTRIES or fn.__name__.startswith({PYTHON_PREFIXES!r}):\n"
            "            return _njit(error_model='numpy', no_cfunc_wrapper=True, **kw)(fn)\n"
            "        kw['cache'] = False   # its callers' cache files hold its code\n"
            "        d = _njit(error_model='numpy', no_cfunc_wrapper=True, no_cpython_wrapper=True,\n"
            "                  **kw)(fn)\n"
            "        d.__class__ = Internal   # no Python entry point: a call from Python raises\n"
            "        return d\n"
            "    return jit\n\n\n"
            f"N = {n}\nNEWTON_MAXIT = {int(newton_maxit)}\n"
            f"COMPENSATED = {bool(compensated)}  # the method option sum (methods/summation.py)\n"
            + kernel_constants() + slot_constants() + event_constants())


def module_source(problem, method_cfg, keyed: bool = False) -> tuple[str, dict]:
    """The full text of a cell's module, and the problem metadata. ``keyed``: the text is only
    hashed into the kernel key (:attr:`Context.keyed`)."""
    from gnibench.methods.events import grid_functions, section_functions, variant
    from gnibench.methods.kernels import driver, linalg, newton
    from gnibench.methods.summation import carry_source, compensated
    from gnibench.problems.codegen import problem_code

    ptext, meta = problem_code(problem.record)
    mods = method_cfg.modifiers
    fields = [m for m in mods if m.record.kind == "field"]
    offsets = []
    off = len(problem.record.model_params)
    for m in mods:
        offsets.append(off)
        off += m.record.runtime_size(m.values)
    # the method's runtime options, then its runtime data, follow the modifiers' values in par
    # (suite/cell/compiled.py)
    runtime = method_cfg.base.record.runtime
    par_at = {name: off + i for i, name in enumerate(runtime)}
    ctx = Context(n=meta["n"], meta=meta, values=method_cfg.base.values, modified=bool(fields),
                  explicit_u=meta["explicit_u"] and not fields,
                  explicit_v=meta["explicit_v"] and not fields, problem=problem.record,
                  keyed=keyed, extra={"par_at": par_at, "data_at": off + len(runtime)})
    head = _header(meta["n"], method_cfg.base.values.get("newton_maxit", 50),
                   compensated(method_cfg.base.values))
    if problem.record.post_step is not None:
        post = template(problem.record.post_step)
    else:
        post = "\n@njit(cache=True, inline='always')\ndef post_step(y, par):\n    return y\n"
    n = meta["n"]
    body = [head, ptext, post, tuple_helpers(n), carry_source(n),
            template(linalg.lu_solve, inline=True), template(newton.newton_done, inline=True), field_source(ctx, mods, offsets),
            template(driver.record_row, inline=True), method_cfg.base.record.generate(ctx),
            variant(driver.integrate, "integrate"), template(driver.partial_fixed),
            grid_functions("fixed", "partial_fixed"),
            variant(driver.integrate, "integrate_grid", "GRID",
                    rename={"grid_rows": "grid_rows_fixed"})]
    if problem.record.sections:    # the section drivers' helpers, Hénon's trick on the cell's f
        # (the problem's module's locator when f is the problem's field: compiled once per problem)
        shared = "" if fields else problem_module_name(problem)
        body += [section_functions(n, shared),
                 variant(driver.integrate, "integrate_section", "SECTION")]
    return "\n".join(body), meta


#: The functions written into their callers (:func:`gnibench.suite.foundation.inline.inline_source`)
#: when a module is written to the cache, besides the helpers the generators mark
#: ``inline='always'`` (their definitions stay, for Python): in a cell's module the problem's and
#: the modifiers' functions (into ``f``, ``fjac``, the modifiers' terms and projections); in a
#: problem's module the integrals and ``invariants`` (into ``eval_invariants``, one function).
INLINED = {"cell": re.compile(r"(base_f|base_jac|(integral|grad|partial|pgrad|pl)_\d+"
                              r"|mod\d+_(term|jac))"),
           "problem": re.compile(r"invariants|integral_\d+")}


def _inline(text: str, prefix: str) -> str:
    names = {name for name in re.findall(r"^def (\w+)\(", text, re.M)
             if INLINED[prefix].fullmatch(name)}
    return inline_source(text, names)


def problem_source(problem) -> tuple[str, dict]:
    """The text of a problem's own module: its generated functions (field, Jacobian, integrals
    and gradients, sections) and ``eval_invariants``, shared by every cell of the problem to
    evaluate the first integrals at the samples (compiled cells, external engines, transforms)."""
    from gnibench.methods.events import henon_source, locate_all_source
    from gnibench.methods.kernels import driver
    from gnibench.problems.codegen import problem_code

    ptext, meta = problem_code(problem.record)
    q = len(meta["integrals"])
    parts = [_header(meta["n"]), ptext, tuple_helpers(meta["n"]),
             "\n" + store_source("store_integrals", q),
             template(driver.eval_invariants, {"store": "store_integrals"})]
    if problem.record.sections:    # Hénon's trick on the base field, for scanned samples
        parts += [henon_source(meta["n"], "base_f"), locate_all_source()]
    return "\n".join(parts), meta


_loaded: dict[str, Any] = {}


def _import(text: str, prefix: str):
    """Import a generated module from the kernel cache (writing it there first if needed).

    The file is named by the hash of the generated text (and of the inliner's source and
    ``INLINED``) and holds
    that text with the small functions written into their callers (:func:`_inline`; done once,
    when the file is written: it costs more than generating the text), under a first line with
    the checksum of the rest."""
    key = _module_key(text, prefix)
    if key in _loaded:
        return _loaded[key]
    install_typing_memo()         # numba asks the same typing question once (numba_typing.py)
    numba_passes.install()        # no closure pass where there is no closure (numba_passes.py)
    datastack.install()           # no frame-stack chunk mapped and unmapped per call (datastack.py)
    path = _module_path(key, prefix)
    if path.exists():
        damaged = "is corrupt or was modified (its checksum does not match)"
        try:
            if _intact(read_regular(path).decode()):
                damaged = ""
        except NotRegularFile as e:                    # a FIFO in its place, say
            damaged = e.what
        except (OSError, UnicodeDecodeError):
            pass
        if damaged:
            warn(f"cached kernel module {path.name} {damaged}; discarded and rebuilt")
            discard(path)
            for f in path.parent.glob(f"__pycache__/{path.stem}.*"):
                discard(f)
    if not path.exists():
        write_atomic(path, _sealed(_inline(text, prefix)))
    verify_numba_files(path)
    name = f"gnibench_{prefix}_{key}"
    spec = importlib.util.spec_from_file_location(name, path)
    kernel = importlib.util.module_from_spec(spec)
    sys.modules[name] = kernel
    spec.loader.exec_module(kernel)
    _loaded[key] = kernel
    return kernel


def _module_key(text: str, prefix: str) -> str:
    """The name of a generated module's file: the hash of its text, of the inliner's source and of
    what it is told to write inline (they decide the file's text too)."""
    return hashlib.sha256((text + INLINED[prefix].pattern + _inliner_digest()).encode()
                          ).hexdigest()[:20]


def _module_path(key: str, prefix: str) -> Path:
    return cache_dir("kernels") / f"{prefix}_{key}.py"


_found: set[str] = set()          # the modules compiled_before found in the kernel cache


def compiled_before(text: str, prefix: str = "cell") -> bool:
    """Whether the module of this text is in the kernel cache with numba's files beside it (a
    guess for scheduling, not a check: :func:`_import` verifies what it loads). A module found
    once is not looked for again in this process: the look is a listing of numba's cache
    directory, and a runner asks it for every cell it plans."""
    key = _module_key(text, prefix)
    if key in _loaded or key in _found:
        return True
    path = _module_path(key, prefix)
    if path.exists() and any(numba_cache_path(path).glob(f"{path.stem}.*.nbi")):
        _found.add(key)
        return True
    return False


@functools.cache
def _inliner_digest() -> str:
    from gnibench.suite.foundation import inline

    return hashlib.sha256(Path(inline.__file__).read_bytes()).hexdigest()


def _sealed(text: str) -> str:
    return f"# sha256 {hashlib.sha256(text.encode()).hexdigest()}\n{text}"


def _intact(stored: str) -> bool:
    head, _, rest = stored.partition("\n")
    return head == f"# sha256 {hashlib.sha256(rest.encode()).hexdigest()}"


def load(problem, method_cfg):
    """Import (generating if needed) the cell's compiled module. Returns (module, meta, seconds).
    A problem with a section has its own module imported first: a cell of its unchanged field
    calls that module's Hénon locator (:func:`problem_module_name`)."""
    t0 = time.perf_counter()
    if problem.record.sections:
        load_problem(problem)
    text, meta = module_source(problem, method_cfg)
    return _import(text, "cell"), meta, time.perf_counter() - t0


def problem_module_name(problem) -> str:
    """The name under which the problem's own module is imported (:func:`load_problem`)."""
    return f"gnibench_problem_{_module_key(problem_source(problem)[0], 'problem')}"


def load_problem(problem):
    """Import (generating if needed) the problem's own compiled module: (module, meta)."""
    text, meta = problem_source(problem)
    return _import(text, "problem"), meta


@functools.cache
def _frozen_by_owner() -> bool:
    """Whether the process was frozen when gnibench first compiled in it (asked once:
    ``gc.get_freeze_count`` walks the frozen objects)."""
    return gc.get_freeze_count() > 0


@contextlib.contextmanager
def compiling():
    """While numba compiles (or loads) a cell, the objects alive before are frozen for Python's
    cyclic garbage collector (``gc.freeze``; unfrozen after, nothing is lost): numba allocates
    millions of objects, and each full collection it triggers walked the ~250 000 objects of a
    loaded gnibench (measured: 0.1 s each, 0.24 s of the 1.4 s of a cold kepler-2d dopri5 cell,
    0.5 s of a section cell's 4.4 s). The compiler's own garbage is still collected. A process
    whose collector is disabled, or frozen by its owner when gnibench first compiles in it, is
    left as it is (``gc.get_freeze_count`` walks the frozen objects: asked once per process, as
    the test processes freeze millions, tests/conftest.py)."""
    if not gc.isenabled() or _frozen_by_owner():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


#: module file -> numba cache misses of its functions when this process last recorded it
_recorded: dict[str, int] = {}


def _misses(kernel) -> int:
    return sum(sum(f.stats.cache_misses.values()) for f in vars(kernel).values()
               if hasattr(f, "stats") and hasattr(f.stats, "cache_misses"))


def forget(*kernels) -> bool:
    """Drop generated modules whose numba cache files failed to load (a ``.nbc`` damaged in a
    way its manifest does not show, e.g. rewritten together with the manifest): their numba cache
    files are removed and the next :func:`load_module` of the same text imports and compiles them
    afresh. True if any of them had cache files."""
    had = False
    for kernel in kernels:
        for key, loaded in list(_loaded.items()):
            if loaded is kernel:
                del _loaded[key]
        sys.modules.pop(kernel.__name__, None)
        _recorded.pop(kernel.__file__, None)
        had |= discard_numba_files(Path(kernel.__file__))
    return had


def record_compiled(*kernels) -> None:
    """Record the checksums of the numba cache files of generated modules (after they compiled or
    loaded what a cell runs; see :func:`gnibench.suite.foundation.cache.record_numba_files`).

    numba writes cache files only when it compiles (a cache miss), so a module recorded before
    in this process with no miss since is skipped: listing the shared ``__pycache__`` costs more
    than a small cell."""
    for kernel in kernels:
        misses = _misses(kernel)
        if _recorded.get(kernel.__file__) == misses:
            continue
        record_numba_files(Path(kernel.__file__))
        _recorded[kernel.__file__] = misses
