"""Off-screen rendering, forced in one place: every picture the project makes comes from here.

PyVista (VTK) and matplotlib never open a window: reports are built on headless machines.
"""
from __future__ import annotations

import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")


def plotter(window_size: tuple[int, int] = (1200, 900)):
    """A PyVista plotter that renders off screen (white background, anti-aliased)."""
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkLogger
    # VTK tries an X display before falling back to EGL; without a display that try only warns.
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    pv.OFF_SCREEN = True
    p = pv.Plotter(off_screen=True, window_size=list(window_size))
    p.set_background("white")
    p.enable_anti_aliasing("ssaa")
    return p


def figure(*args, **kwargs):
    """A matplotlib figure on the Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt.subplots(*args, **kwargs)


def save_figure(fig, path) -> None:
    """Save atomically and close (a killed run leaves no half-written PNG)."""
    from geometry.artifacts import atomic_path
    import matplotlib.pyplot as plt
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight", format=str(path).rsplit(".", 1)[-1])
    plt.close(fig)


def screenshot(p, path) -> None:
    """Render a PyVista plotter to PNG atomically and close it."""
    from geometry.artifacts import atomic_path
    with atomic_path(path) as tmp:
        p.screenshot(str(tmp))
    p.close()
