"""The gnibench documentation's own Sphinx extension: the pages generated from the code.

When the build starts (``builder-inited``) it writes, into the source tree (git-ignored, see
``docs/.gitignore``):

* ``reference/{problems,methods,modifiers,metrics}/``: one page per registry record
  (:mod:`.registry`), and ``reference/ids.md``, the catalogue of public ids (:mod:`.catalogue`);
* ``reference/claims/``: the catalogue of the claims ledger (:mod:`.claims`);
* ``reference/cli.md`` and ``reference/api.md``: the command line's help and the API's
  docstrings (:mod:`.interfaces`);
* ``reference/performance.md``: the newest saved benchmark runs (:mod:`.performance`);
* ``gallery/figures/``: the seeds' figures drawn by this build beside their verdicts
  (:mod:`.gallery`).

It also adds the directives ``gnibench-schema`` (the key tables of the TOML schemas) and
``gnibench-statuses`` (the statuses, from their enum), and
orders the globs of ``toctree`` (:mod:`.toctree`).
Files are written only when their text changes, so an incremental build re-reads only those.
The generators import nothing of Sphinx, so that the tests (``tests/docs/``) can run them.
"""
from __future__ import annotations

from pathlib import Path


def generate(app) -> None:
    from . import catalogue, claims, gallery, interfaces, performance, registry

    srcdir = Path(app.srcdir)
    repo = srcdir.parent
    registry.write(srcdir)
    catalogue.write(srcdir)
    claims.write(srcdir)
    interfaces.write(srcdir)
    performance.write(srcdir, repo)
    gallery.write(srcdir, Path(app.outdir).parent / "seeds")


def setup(app):
    from . import interfaces, toctree     # Sphinx's modules: the generators above need none

    app.connect("builder-inited", generate)
    app.add_directive("gnibench-schema", interfaces.SchemaDirective)
    app.add_directive("gnibench-statuses", interfaces.StatusesDirective)
    app.add_directive("toctree", toctree.OrderedTocTree, override=True)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
