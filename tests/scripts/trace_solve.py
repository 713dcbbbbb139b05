"""Which files of gnibench, and which of its classes, a command passes through (issue 44, item 3).

usage: python tests/scripts/trace_solve.py solve kepler-2d rk4:h=0.01 --t-end 10 [--load F.toml]

The command runs twice in one process: the first call imports the registries and compiles or
loads the kernels, the second is traced with :func:`sys.setprofile`. Printed: the package files
whose functions ran, the gnibench classes instantiated (``record``: a dataclass), and how many
times the checks of a cell ran (the horizon ``grid``, the budgets, ``every``, ``dt_out``, the
initial point ``y0``). Set FUNCS=1 to list the functions per file.
"""
import collections
import contextlib
import dataclasses
import io
import os
import sys

import gnibench

ROOT = os.path.dirname(gnibench.__file__)
WATCH = {"grid", "check_budgets", "check_dt_out", "check_integer", "effective_dt_out", "y0",
         "check_initial_point", "grid_step", "check_count", "check_output"}
files: dict[str, set[str]] = {}
types: collections.Counter = collections.Counter()
calls: collections.Counter = collections.Counter()


def profile(frame, event, arg):
    if event != "call":
        return
    code = frame.f_code
    if code.co_name == "__init__":         # a dataclass's __init__ is generated: no file of ours
        cls = type(frame.f_locals.get("self"))
        if cls.__module__.startswith("gnibench"):
            mark = "record" if dataclasses.is_dataclass(cls) else "class"
            types[f"{mark} {cls.__module__}.{cls.__qualname__}"] += 1
    if not code.co_filename.startswith(ROOT):
        return
    files.setdefault(os.path.relpath(code.co_filename, ROOT), set()).add(code.co_name)
    if code.co_name in WATCH:
        calls[code.co_name] += 1


def main(argv: list[str]) -> None:
    from gnibench.suite.cli.main import main as command

    with contextlib.redirect_stdout(io.StringIO()):
        command(argv)                       # warm: registries imported, kernels loaded
    sys.setprofile(profile)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            code = command(argv)
    finally:
        sys.setprofile(None)
    print(f"exit {code}")
    print(f"{len(files)} files:")
    for name in sorted(files):
        print(f"   {name}", " ".join(sorted(files[name])) if os.environ.get("FUNCS") else "")
    records = sum(t.startswith("record") for t in types)
    print(f"{len(types)} classes, {records} record types (dataclasses):")
    for name, n in sorted(types.items()):
        print(f"   {name} x{n}")
    print("checks run:", dict(sorted(calls.items())))


if __name__ == "__main__":
    main(sys.argv[1:])
