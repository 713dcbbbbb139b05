"""Mark a cosmic-ray session's mutants of type annotations as equivalent (README.md beside this file).

``python equivalent.py SESSION.sqlite``: every module in scope has ``from __future__ import
annotations``, so an annotation (``jobs: int | None``, ``-> dict``) is a string that nothing
evaluates (the dataclasses here do not; the pydantic records, which do, are out of scope): a
mutant inside one (``int | None`` -> ``int // None``) cannot change behaviour. They are marked
skipped with the output "equivalent: annotation" (pending ones only) and counted apart.
"""
from __future__ import annotations

import ast
import sys
from functools import lru_cache

from cosmic_ray.work_db import WorkDB, use_db
from cosmic_ray.work_item import WorkerOutcome, WorkResult

EQUIVALENT = "equivalent: annotation"


@lru_cache(maxsize=None)
def annotation_spans(path: str) -> tuple:
    tree = ast.parse(open(path, encoding="utf-8").read())
    if not any(isinstance(n, ast.ImportFrom) and n.module == "__future__"
               and any(a.name == "annotations" for a in n.names) for n in tree.body):
        return ()
    spans = []
    for node in ast.walk(tree):
        notes = []
        if isinstance(node, ast.arg) and node.annotation is not None:
            notes.append(node.annotation)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.returns:
            notes.append(node.returns)
        elif isinstance(node, ast.AnnAssign):
            notes.append(node.annotation)
        spans += [((n.lineno, n.col_offset), (n.end_lineno, n.end_col_offset)) for n in notes]
    return tuple(spans)


def in_annotation(path: str, pos: tuple) -> bool:
    return any(a <= tuple(pos) < b for a, b in annotation_spans(path))


def main(session: str) -> None:
    with use_db(session, WorkDB.Mode.open) as db:
        marks = [w.job_id for w in db.pending_work_items
                 if in_annotation(str(w.mutations[0].module_path), w.mutations[0].start_pos)]
        db.set_multiple_results(marks, WorkResult(worker_outcome=WorkerOutcome.SKIPPED,
                                                  output=EQUIVALENT))
        print(f"{len(marks)} pending mutants in annotations marked equivalent")


if __name__ == "__main__":
    main(sys.argv[1])
