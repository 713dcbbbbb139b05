"""``gnibench.load``: define the problems and methods of a TOML file of user definitions, as the
command line's ``--load FILE`` (:mod:`gnibench.suite.cell.user`)."""
from __future__ import annotations

from pathlib import Path

from gnibench.suite.api.arguments import api_function


@api_function
def load(path: Path) -> list[str]:
    """Define the problems and methods of a TOML file of user definitions.

    The file's ``[[problem]]`` entries (a vector field and its integrals as expressions) and
    ``[[method]]`` entries (a Butcher tableau, a composition, a Python step or solver) join the
    registries of this process, as the command line's ``--load FILE`` (and ``GNIBENCH_LOAD``);
    they are checked as they are read (declared orders, symplecticity, integrals). Loading a
    file again replaces its definitions.

    Parameters
    ----------
    path : path
        The TOML file.

    Returns
    -------
    list of str
        The ids the file defines.

    Raises
    ------
    gnibench.UserError
        A file that cannot be read, or a bad definition (naming the entry and its key).

    Examples
    --------
    >>> import gnibench, pathlib, tempfile
    >>> defs = pathlib.Path(tempfile.mkdtemp()) / "defs.toml"
    >>> _ = defs.write_text('''
    ... [[problem]]
    ... id = "my-oscillator"
    ... title = "harmonic oscillator"
    ... states = ["q", "p"]
    ... hamiltonian = "p^2/2 + q^2/2"
    ... initial = {q = 1, p = 0}
    ... ''')
    >>> gnibench.load(defs)
    ['my-oscillator']
    >>> gnibench.solve("my-oscillator", "stormer-verlet:h=0.1", steps=10).status
    'ok'
    """
    from gnibench.suite.cell.user.loader import load as load_file

    return load_file(path)
