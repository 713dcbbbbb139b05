"""The identity checks of the ledger ([I] claims): small computations, no long integration.

Each check returns named values for the claim's ``measured``/``passes`` expressions (a
``measured`` value when there is one natural number to show). The checks of [B] are in
:mod:`.identities_b`, those of [HLW] in :mod:`.identities_hlw`; shared helpers in
:mod:`.identity_tools`; this module is the registry.
"""
from __future__ import annotations

import numpy as np
from gnibench.suite.ledger import identities_b, identities_b41, identities_hlw, identities_slips


def _registry() -> dict:
    return {**identities_b.CHECKS, **identities_b41.CHECKS, **identities_hlw.CHECKS,
            **identities_slips.CHECKS}


def names() -> list[str]:
    return sorted(_registry())


def run(name: str) -> dict:
    checks = _registry()
    if name not in checks:
        raise KeyError(f"unknown check {name!r} (known: {', '.join(sorted(checks))})")
    with np.errstate(all="ignore"):
        return checks[name]()
