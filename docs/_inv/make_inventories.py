"""Write the small intersphinx inventories of NumPy, heyoka.py, rebound and Matplotlib (docs/_inv/*.inv).

The documentation must build without a network (CI reaches only the package registries), so
every inventory that ``conf.py``'s ``intersphinx_mapping`` reads is a file in this folder:

* ``python.inv``, ``scipy.inv``, ``pandas.inv``: the inventories that Debian's documentation
  packages ship (``python3.11-doc``, ``python-scipy-doc`` 1.10.1, ``python-pandas-doc`` 1.5.3:
  ``apt-get download`` them and copy ``usr/share/doc/*/html/objects.inv``). Their paths are those
  of the online documentation, which has kept them.
* ``numpy.inv``, ``heyoka.inv``, ``rebound.inv``, ``matplotlib.inv``: written by this script from the entries below,
  the objects our pages and docstrings name, at the paths of the projects' online documentation
  (NumPy's and Matplotlib's generated reference pages, heyoka.py's ``autosummary_generated`` pages, rebound's
  mkdocs pages). Add an entry here when a page names another object, then run::

      python docs/_inv/make_inventories.py

The format is Sphinx's inventory version 2: four header lines, then zlib-compressed lines
``name domain:role priority uri display`` (``$`` in the entries below stands for the name).
"""
from __future__ import annotations

import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent

INVENTORIES = {
    "numpy": ("NumPy", "2", [
        ("numpy", "py:module", "reference/index.html#module-$"),
        ("numpy.ndarray", "py:class", "reference/generated/$.html#$"),
        ("numpy.float64", "py:class", "reference/arrays.scalars.html#$"),
        ("numpy.int64", "py:class", "reference/arrays.scalars.html#$"),
        ("numpy.longdouble", "py:class", "reference/arrays.scalars.html#$"),
        ("numpy.random.Generator", "py:class", "reference/random/generator.html#$"),
        ("numpy.array_equal", "py:function", "reference/generated/$.html#$"),
        ("numpy.allclose", "py:function", "reference/generated/$.html#$"),
    ]),
    "heyoka": ("heyoka.py", "7", [
        ("heyoka", "py:module", "index.html#module-$"),
        ("heyoka.taylor_adaptive", "py:class", "autosummary_generated/$.html#$"),
        ("heyoka.taylor_adaptive_batch", "py:class", "autosummary_generated/$.html#$"),
    ]),
    "matplotlib": ("Matplotlib", "3", [
        ("matplotlib.figure.Figure", "py:class", "api/_as_gen/$.html#$"),
        ("matplotlib.axes.Axes", "py:class", "api/_as_gen/$.html#$"),
    ]),
    "rebound": ("REBOUND", "4", [
        ("rebound", "py:module", "#"),
        ("rebound.Simulation", "py:class", "simulation/"),
    ]),
}


def inventory(project: str, version: str, entries: list[tuple[str, str, str]]) -> bytes:
    """The bytes of a Sphinx inventory (version 2) holding ``entries``."""
    header = (f"# Sphinx inventory version 2\n# Project: {project}\n# Version: {version}\n"
              "# The remainder of this file is compressed using zlib.\n")
    body = "".join(f"{name} {role} 1 {uri.replace('$', name)} -\n" for name, role, uri in entries)
    return header.encode() + zlib.compress(body.encode())


def main() -> None:
    for name, (project, version, entries) in INVENTORIES.items():
        (HERE / f"{name}.inv").write_bytes(inventory(project, version, entries))


if __name__ == "__main__":
    main()
