"""MkDocs hook: fit the rendered pages to the theme and to docstrings written for Sphinx-style readers.

* Section ids that start with a digit ("## 1. The table" → ``1-the-table``) are not valid CSS selectors; the
  theme's scroll tracking throws on them and stops its other scripts (tables lose their styling).  They get an
  ``s-`` prefix, in the page and in its table of contents.
* Docstrings name other objects with Sphinx roles (``:func:`safe_height```), which mkdocstrings shows
  literally; the role is dropped and the name kept as code (``~a.b.Name`` as ``Name``, as Sphinx shows it).
"""

from __future__ import annotations

import re

_DIGIT_ID = re.compile(r'(id="|href="#)(\d)')
_ROLE = re.compile(r":(?:func|mod|class|meth|data|attr|obj):(?=<code>)")
_SHORT = re.compile(r"<code>~(?:[\w.]+\.)?(\w+)</code>")


def _retarget(items) -> None:
    for item in items:
        if item.id[:1].isdigit():
            item.id = "s-" + item.id
        _retarget(item.children)


def on_page_content(html, page, config, files):
    _retarget(page.toc)
    return _SHORT.sub(r"<code>\1</code>", _ROLE.sub("", _DIGIT_ID.sub(r"\1s-\2", html)))
