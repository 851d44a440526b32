"""The web app (issue 16): ``fruitimpact serve`` starts a local server of pages that explore an impact.

Optional: it needs the ``[app]`` extra (tornado).  ``server`` serves the pages and a JSON API; ``explorer``
computes what the explorer shows with the library's own functions; ``static`` holds the pages, their scripts
(charts drawn as SVG by ``charts.js``, no chart library) and their style.  Nothing comes from another origin.
"""
