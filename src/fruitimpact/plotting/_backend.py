"""The matplotlib backend and atomic saving of figures.

matplotlib is an optional extra (``plot``): it is imported here, on first
use, and nowhere else in fruitimpact.
"""

from __future__ import annotations

from fruitimpact.impact.outputs import FIGURE_FORMATS, atomic_write, output_format


def _pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (unless a module backend was chosen)."""
    try:
        import matplotlib

        matplotlib.use("Agg", force=False) if not matplotlib.get_backend().lower().startswith("module") else None
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ImportError("plotting needs matplotlib: pip install 'fruitimpact[plot]'") from exc
    return plt


def save_figure(fig, path, argument: str = "path") -> None:
    """Save ``fig`` to ``path`` atomically (a kill or full disk leaves the old file or none) and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        Ends in .png, .svg or .pdf: the format follows the extension.
    argument : str
        The option that named ``path`` (``--plot``), for the one-line ``ValueError``
        about an unsupported extension or a file that cannot be written.
    """
    plt = _pyplot()
    try:
        fmt = output_format(path, argument, FIGURE_FORMATS)
        # the temporary name has no extension: the format is passed explicitly
        atomic_write(path, lambda tmp: fig.savefig(tmp, format=fmt, dpi=150), argument)
    finally:
        plt.close(fig)
