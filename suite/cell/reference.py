"""Reference solutions: what ``global_error`` is measured against.

Three backends:

* ``exact``: the problem's exact solution (``Problem.exact``), evaluated in double. It is cheap and
  not cached. Its accuracy is limited by double round-off in the phase, and that limit grows with t:
  kepler-2d at t = 1000 periods is good to about 2e-11 (measured against a real128 reference).
* ``heyoka``: Taylor integration of the problem's sympy model (:func:`gnibench.methods.engines.heyoka.heyoka_propagate`)
  in double, long double or real128, with ``tol`` = the epsilon of the precision by default.
* ``rebound``: IAS15 on N-body problems with a rebound adapter (:data:`gnibench.methods.engines.rebound.ADAPTERS`), in
  double, with ``tol`` = IAS15's epsilon (rebound's default 1e-9).

Accuracy of the defaults (a backend named without ``tol``), against a 40-digit evaluation of the
Kepler orbit over ten periods (tests/cell/test_reference_defaults.py; bounds 10x the measured
values): on kepler-2d (e = 0.6) the exact solution and heyoka in long double are
within 4 ulps of 1 (8.9e-16), heyoka in double within 3e-12, IAS15 (epsilon 1e-9) within 5e-12; on
the eccentric e = 0.9 orbit within 2e-14, 1e-13, 3e-9 and 2e-10. A tolerance of 1e-9 instead of
the precision's epsilon would leave every reference wrong at ~3e-8 (every work-precision diagram
would flatten there).

The accuracy of an integrated reference is checked where it is used
(:func:`reference_accuracy`): a second reference, the same engine and precision at a tolerance
:data:`CHECK_FACTOR` times looser, is computed on the same grid, and the distance of the two at
each sample is the reference's own accuracy estimate (an upper bound of its error wherever the
engine's error grows with its tolerance, as a Taylor method's and IAS15's do; at the round-off
floor both carry the same size of error). Errors of a method below that estimate do not measure
the method: the tables mark them and the reports leave them out of ranks and fits. The exact
solution has no estimate (its double round-off, above, is far below the errors measured).

The integrated references are cached on disk under ``<cache>/references``. A file's key is the
problem's canonical spec and source hash, a hash of the grid, the backend, precision, tolerance and
engine version, so a second request for the same reference only reads the file. A reference spec
uses the spec syntax, e.g. ``heyoka:precision=real128,tol=1e-30`` (see :func:`parse_reference`).
"""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from importlib.metadata import version

import numpy as np
from gnibench.methods.engines.heyoka import epsilon, precision_name
from gnibench.suite.cell.spec import parse_item
from gnibench.suite.foundation.cache import cache_dir, discard, read_checked, warn, write_checked
from gnibench.suite.foundation.errors import UserError, named
from gnibench.suite.foundation.params import Param, bind

BACKENDS = ("exact", "heyoka", "rebound")
FORMAT = 2                                     # bump when the cached content changes meaning

_PRECISION = Param("precision", "double", "working precision", kind="str",
                   choices=("double", "long double", "long-double", "real128"))
SCHEMAS = {
    "exact": (),
    "heyoka": (_PRECISION, Param("tol", None, "Taylor tolerance (default: epsilon of the precision)",
                                 low=0.0, low_open=True)),
    "rebound": (Param("tol", None, "IAS15 epsilon (default: rebound's 1e-9)", low=0.0,
                      low_open=True),),
}


@dataclass(frozen=True)
class ReferenceSpec:
    """A resolved reference choice: backend, precision and tolerance (None for exact)."""

    backend: str
    precision: str = "double"
    tol: float | None = None

    def text(self) -> str:
        if self.backend == "exact":
            return "exact"
        opts = (f"precision={self.precision}," if self.backend == "heyoka" else "") + f"tol={self.tol!r}"
        return f"{self.backend}:{opts}"

    def describe(self) -> dict:
        return {"backend": self.backend, "precision": self.precision, "tol": self.tol,
                "spec": self.text()}


@dataclass
class ReferenceSolution:
    """A reference on a grid: float64 samples and, above double, the full-precision ones."""

    spec: ReferenceSpec
    t: np.ndarray
    y: np.ndarray
    y_full: np.ndarray | None = None
    cached: bool = False
    seconds: float = 0.0
    info: dict = field(default_factory=dict)


def resolve(backend: str, precision: str = "double", tol: float | None = None,
            problem=None) -> ReferenceSpec:
    """Validate a reference choice (against a problem record, if given) and fill in defaults."""
    if backend not in BACKENDS:
        raise UserError(f"unknown reference {backend!r}; allowed: {'|'.join(BACKENDS)}|none")
    precision = precision_name(precision)
    if backend != "heyoka" and precision != "double":
        raise UserError(f"reference {backend} runs in double only; precision={precision} "
                        f"is for the heyoka reference")
    if tol is not None and not (float(tol) > 0):
        raise UserError(f"bad reference tol={tol}; allowed: a number > 0")
    if problem is not None:
        if backend == "exact" and problem.exact is None:
            raise UserError(f"problem {problem.id} has no exact solution; use a heyoka reference "
                            f"({named('--reference', 'heyoka')})")
        if backend == "rebound":
            from gnibench.methods.engines.rebound import adapter

            adapter(problem)
        if backend == "heyoka":
            from gnibench.methods.engines.heyoka import check_heyoka

            check_heyoka(problem)
    if backend == "exact":
        return ReferenceSpec("exact")
    if tol is None:
        tol = epsilon(precision) if backend == "heyoka" else 1e-9
    return ReferenceSpec(backend, precision, float(tol))


def parse_reference(text: str | None, problem=None) -> ReferenceSpec | None:
    """Resolve a reference spec (``exact``, ``heyoka:precision=real128,tol=1e-30``, ``rebound``,
    ``none``); None or ``none`` gives None."""
    if text is None or str(text).strip().lower() == "none":
        return None
    name, given = parse_item(str(text), "reference")
    if name not in BACKENDS:
        raise UserError(f"unknown reference {name!r}; allowed: {'|'.join(BACKENDS)}|none")
    values = bind(SCHEMAS[name], given, f"reference {name}")
    return resolve(name, values.get("precision", "double"), values.get("tol"), problem)


def default_reference(problem) -> ReferenceSpec | None:
    """What global_error is measured against when nothing is chosen: the exact solution, if any."""
    return ReferenceSpec("exact") if problem.exact is not None else None


def _key(problem_bound, t: np.ndarray, spec: ReferenceSpec) -> str:
    from gnibench.problems.codegen import _source_hash
    from gnibench.suite.foundation.provenance import code_digest

    engine = {"heyoka": "heyoka", "rebound": "rebound"}[spec.backend]
    doc = {"format": FORMAT, "problem": problem_bound.text(),
           "source": _source_hash(problem_bound.record),
           "grid": hashlib.sha256(np.ascontiguousarray(t, dtype=np.float64).tobytes()).hexdigest(),
           "backend": spec.backend, "precision": spec.precision, "tol": repr(spec.tol),
           "engine": f"{engine} {version(engine)}",
           "engine_code": code_digest("gnibench.methods.engines.base",
                                      f"gnibench.methods.engines.{engine}")}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:24]


def cache_path(problem_bound, t: np.ndarray, spec: ReferenceSpec):
    """The file that holds (or will hold) this reference."""
    tag = spec.precision.replace(" ", "-")
    return cache_dir("references") / f"{problem_bound.id}-{spec.backend}-{tag}-{_key(problem_bound, t, spec)}.npz"


def _full_from_text(text: np.ndarray, precision: str) -> np.ndarray:
    from gnibench.methods.engines.heyoka import fp_type

    fp = fp_type(precision)
    flat = [fp(s) for s in text.ravel()]
    return np.array(flat).reshape(text.shape)


_verified: set[tuple[str, str]] = set()


def _read(path, spec: ReferenceSpec, t: np.ndarray, problem_bound=None) -> ReferenceSolution | None:
    """A cached reference whose checksum matches, whose grid is ``t`` and whose content passes
    the checks of :mod:`.reference_checks` (with ``problem_bound``), or None (rebuild)."""
    import io

    raw = read_checked(path, "reference solution")
    if raw is None:
        return None
    try:
        with np.load(io.BytesIO(raw), allow_pickle=False) as z:
            if not np.array_equal(z["t"], t):
                raise ValueError("another grid")
            y = np.asarray(z["y"], dtype=np.float64)
            full = _full_from_text(z["y_full"], spec.precision) if "y_full" in z.files else None
            info = json.loads(str(z["info"]))
    except Exception:  # noqa: BLE001 - not an npz, or not ours: rebuilt, whatever it is
        warn(f"cached reference solution {path.name} does not hold what its name says; "
             f"discarded and rebuilt")
        discard(path)
        return None
    seen = (str(path), hashlib.sha256(raw).hexdigest())
    if problem_bound is not None and seen not in _verified:
        from gnibench.suite.cell.reference_checks import problem_ok

        why = problem_ok(problem_bound, t, y, full)
        if why:
            warn(f"cached reference solution {path.name} is not a solution of "
                 f"{problem_bound.id}: {why}; discarded and rebuilt")
            discard(path)
            return None
        _verified.add(seen)             # this process checked these very bytes already
    return ReferenceSolution(spec, t, y, full, cached=True, info=info)


def _write(path, sol: ReferenceSolution) -> None:
    import io

    arrays = {"t": sol.t, "y": sol.y, "info": np.array(json.dumps(sol.info, default=str))}
    if sol.y_full is not None:
        arrays["y_full"] = np.array([str(v) for v in sol.y_full.ravel()]).reshape(sol.y_full.shape)
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_checked(path, buffer.getvalue())


def reference_solution(problem_bound, t_grid, backend: str | ReferenceSpec = "exact",
                       precision: str = "double", tol: float | None = None) -> ReferenceSolution:
    """The reference of a bound problem on ``t_grid`` (from the disk cache when possible).

    Parameters
    ----------
    problem_bound:
        A parsed problem (:func:`gnibench.suite.cell.spec.parse_problem`).
    t_grid:
        Sample times, increasing from 0.
    backend, precision, tol:
        See the module docstring; or pass a resolved :class:`ReferenceSpec` as ``backend``.
    """
    spec = backend if isinstance(backend, ReferenceSpec) else resolve(backend, precision, tol,
                                                                       problem_bound.record)
    t = np.ascontiguousarray(t_grid, dtype=np.float64)
    rec = problem_bound.record
    t0 = time.perf_counter()
    if spec.backend == "exact":
        y = np.asarray(rec.exact(t, rec.y0(problem_bound.values), problem_bound.values), float)
        return ReferenceSolution(spec, t, y, None, seconds=time.perf_counter() - t0)
    if t.ndim != 1 or len(t) == 0 or t[0] < 0 or np.any(np.diff(t) <= 0):
        raise UserError("a reference grid must be a non-empty, increasing array of times >= 0")
    path = cache_path(problem_bound, t, spec)
    sol = _read(path, spec, t, problem_bound)
    if sol is not None:
        sol.seconds = time.perf_counter() - t0
        return sol
    from gnibench.methods.engines.heyoka import heyoka_propagate
    from gnibench.methods.engines.rebound import rebound_propagate

    if spec.backend == "heyoka":
        run = heyoka_propagate(problem_bound, t, spec.precision, spec.tol)
    else:
        run = rebound_propagate(problem_bound, t, "ias15", epsilon=spec.tol)
    if run.status != "ok":
        raise RuntimeError(f"reference {spec.text()} for {problem_bound.text()} failed: {run.reason}")
    info = {**run.info, "steps": int(run.steps[-1]), "seconds": run.seconds,
            "setup_seconds": run.setup_seconds, "problem": problem_bound.text(), **spec.describe()}
    sol = ReferenceSolution(spec, t, run.y, run.y_full, cached=False, info=info)
    _write(path, sol)
    sol.seconds = time.perf_counter() - t0
    return sol


#: how much looser the tolerance of the check reference is than the reference's own
CHECK_FACTOR = 100.0


def check_spec(spec: ReferenceSpec) -> ReferenceSpec | None:
    """The looser reference whose distance to ``spec``'s estimates its accuracy (None: exact)."""
    if spec.backend == "exact":
        return None
    return ReferenceSpec(spec.backend, spec.precision, float(spec.tol) * CHECK_FACTOR)


def reference_accuracy(problem_bound, sol: ReferenceSolution) -> np.ndarray | None:
    """The accuracy estimate of the reference ``sol`` at each of its samples: the Euclidean
    distance to the check reference (:func:`check_spec`, cached like any reference); None for
    the exact solution, NaN where the check reference failed (its reason in a warning)."""
    check = check_spec(sol.spec)
    if check is None:
        return None
    try:
        other = reference_solution(problem_bound, sol.t, check)
    except RuntimeError as e:
        warn(f"the accuracy of reference {sol.spec.text()} is not estimated: {e}")
        return np.full(len(sol.t), np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        return np.sqrt(np.sum((sol.y - other.y) ** 2, axis=1))


def reference(problem_bound, t_grid, backend: str = "exact", precision: str = "double",
              tol: float | None = None) -> np.ndarray:
    """The reference samples (float64, shape (len(t), N)); see :func:`reference_solution`."""
    return reference_solution(problem_bound, t_grid, backend, precision, tol).y
