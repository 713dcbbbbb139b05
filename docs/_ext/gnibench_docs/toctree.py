"""The ``toctree`` directive with ordered globs: explicit entries first, in the order written,
then every document a glob pattern matches that is not listed yet, in natural order
(``b-fig-2`` before ``b-fig-10``).

Sphinx's own directive lists a document twice when an explicit entry and a glob both name it,
and warns when a glob matches nothing; the section indexes need both an order (the pages meant to
be read first) and a glob (so that a new page of the folder is picked up by itself).
"""
from __future__ import annotations

import re

from docutils.statemachine import StringList
from sphinx.directives.other import TocTree
from sphinx.util import docname_join
from sphinx.util.matching import patfilter

_GLOB = re.compile(r".*[*?\[].*")


def natural(name: str):
    return [int(x) if x.isdigit() else x for x in re.split(r"(\d+)", name)]


class OrderedTocTree(TocTree):
    def parse_content(self, toctree):
        if not toctree.get("glob"):
            return super().parse_content(toctree)
        current = self.env.current_document.docname
        found = sorted(self.env.found_docs - {current})
        listed: list[str] = []
        entries = [e.strip() for e in self.content if e.strip()]
        explicit = {docname_join(current, e) for e in entries if not _GLOB.match(e)}
        for entry in entries:
            if _GLOB.match(entry):
                names = sorted(patfilter(found, docname_join(current, entry)), key=natural)
                listed += ["/" + d for d in names if d not in explicit and "/" + d not in listed]
            else:
                listed.append(entry)
        self.content = StringList(listed, source=self.content.source(0) if self.content else "")
        toctree["glob"] = False
        out = super().parse_content(toctree)
        toctree["glob"] = True          # a new page of the folder makes Sphinx read this one again
        return out
