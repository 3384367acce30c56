"""Small matplotlib helpers shared by the pictures: a legend that stays inside its axes."""

from __future__ import annotations

__all__ = ["legend_inside", "legend_fits"]


def _renderer(figure):
    canvas = figure.canvas
    if hasattr(canvas, "get_renderer"):
        return canvas.get_renderer()
    figure.draw_without_rendering()
    return figure._get_renderer()  # noqa: SLF001 (non-Agg backends)


def legend_fits(axes, legend=None) -> bool:
    """Does the legend's drawn box lie inside the axes' box (display units, 1 px slack)?"""
    legend = legend if legend is not None else axes.get_legend()
    if legend is None:
        return True
    renderer = _renderer(axes.figure)
    axes.apply_aspect()
    box, frame = legend.get_window_extent(renderer), axes.get_window_extent(renderer)
    return (box.x0 >= frame.x0 - 1 and box.y0 >= frame.y0 - 1 and box.x1 <= frame.x1 + 1
            and box.y1 <= frame.y1 + 1)


def legend_inside(axes, fontsize: float = 7, layout: bool = True, **options):
    """A legend inside the axes: matplotlib's "best" place, then more columns and a smaller
    font, and as a last resort more room in the data limits (y widened, up to 4 times), until
    the drawn legend lies inside the axes' box. ``layout`` runs tight_layout before each check
    (the axes' final size is what counts)."""
    figure = axes.figure
    handles, labels = axes.get_legend_handles_labels()
    if not handles:
        return None
    entries = len(handles)
    tries = [(1, fontsize), (2, fontsize), (2, fontsize - 1), (3, fontsize - 1),
             (3, fontsize - 2), (4, fontsize - 2)]
    tries = [(ncol, size) for ncol, size in tries if ncol <= max(entries, 1)]
    legend = None
    for _widening in range(5):
        for ncol, size in tries:
            legend = axes.legend(fontsize=size, ncol=ncol, loc=options.get("loc", "best"),
                                 framealpha=0.85)
            if layout:
                figure.tight_layout()
            if legend_fits(axes, legend):
                return legend
        bottom, top = axes.get_ylim()
        axes.set_ylim(bottom, top + (top - bottom) * 0.6)  # room above the data
    return legend
