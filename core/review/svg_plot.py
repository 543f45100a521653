"""Small line plots as inline SVG: the headless report's figures, readable in any browser, no plotting library.

Blender's bundled Python has no matplotlib; SVG is text, so a plot is a string the report embeds.
"""

from __future__ import annotations

from html import escape

import numpy as np


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About ``n`` round tick values covering [lo, hi]."""
    span = hi - lo
    if not np.isfinite(span) or span <= 0:
        return [lo]
    raw = span / max(n - 1, 1)
    mag = 10 ** np.floor(np.log10(raw))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=raw)
    start = np.ceil(lo / step) * step
    return [float(v) for v in np.arange(start, hi + 0.5 * step, step) if v <= hi + 1e-9 * span]


def _fmt(v: float) -> str:
    v = 0.0 if abs(v) < 1e-12 else v          # no "-0"
    return f"{v:.0f}" if abs(v) >= 10 or v == int(v) else f"{v:.2g}"


def line_plot(series, *, title: str, x_label: str, y_label: str, width: int = 720, height: int = 220,
              hlines=(), bands=()) -> str:
    """SVG of the ``series`` [(label, x (n,), y (n,), colour)], NaN breaking a line.

    ``hlines`` [(y, label, colour)] draws dashed reference lines; ``bands`` [(x0, x1, colour)] shades
    x ranges (e.g. camera spells).
    """
    left, right, top, bottom = 56, 12, 26, 34
    xs = [np.asarray(x, dtype=float) for _, x, _, _ in series]
    ys = [np.asarray(y, dtype=float) for _, _, y, _ in series]
    finite_x = np.concatenate([x[np.isfinite(x)] for x in xs] or [np.zeros(0)])
    finite_y = np.concatenate([y[np.isfinite(y)] for y in ys] + [np.array([h[0] for h in hlines], dtype=float)])
    x0, x1 = (float(finite_x.min()), float(finite_x.max())) if finite_x.size else (0.0, 1.0)
    y0, y1 = (float(finite_y.min()), float(finite_y.max())) if finite_y.size else (0.0, 1.0)
    if x1 <= x0:
        x1 = x0 + 1.0
    if y1 <= y0:
        y0, y1 = y0 - 1.0, y1 + 1.0
    pad = 0.05 * (y1 - y0)
    y0, y1 = y0 - pad, y1 + pad
    pw, ph = width - left - right, height - top - bottom

    def px(x):
        return left + (np.asarray(x, dtype=float) - x0) / (x1 - x0) * pw

    def py(y):
        return top + (1.0 - (np.asarray(y, dtype=float) - y0) / (y1 - y0)) * ph

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">',
           f'<text x="{left}" y="16" font-size="13" font-weight="bold">{escape(title)}</text>']
    for a, b, colour in bands:
        xa, xb = float(px(max(a, x0))), float(px(min(b, x1)))
        if xb > xa:
            out.append(f'<rect x="{xa:.1f}" y="{top}" width="{xb - xa:.1f}" height="{ph}" fill="{colour}"/>')
    out.append(f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#999"/>')
    for t in _ticks(y0, y1):
        y = float(py(t))
        out.append(f'<line x1="{left}" x2="{left + pw}" y1="{y:.1f}" y2="{y:.1f}" stroke="#eee"/>'
                   f'<text x="{left - 4}" y="{y + 4:.1f}" text-anchor="end">{_fmt(t)}</text>')
    for t in _ticks(x0, x1, 8):
        x = float(px(t))
        out.append(f'<text x="{x:.1f}" y="{top + ph + 14}" text-anchor="middle">{_fmt(t)}</text>')
    out.append(f'<text x="{left + pw / 2:.0f}" y="{height - 4}" text-anchor="middle">{escape(x_label)}</text>'
               f'<text x="12" y="{top + ph / 2:.0f}" transform="rotate(-90 12 {top + ph / 2:.0f})" '
               f'text-anchor="middle">{escape(y_label)}</text>')
    for y, label, colour in hlines:
        yy = float(py(y))
        out.append(f'<line x1="{left}" x2="{left + pw}" y1="{yy:.1f}" y2="{yy:.1f}" stroke="{colour}" '
                   f'stroke-dasharray="5,4"/><text x="{left + pw - 4}" y="{yy - 3:.1f}" text-anchor="end" '
                   f'fill="{colour}">{escape(label)}</text>')
    legend_x = left + 30 + 8 * len(title)          # legends follow the title on its line
    for (label, _, _, colour), x, y in zip(series, xs, ys):
        ok = np.isfinite(x) & np.isfinite(y)
        runs, current = [], []
        for xi, yi, good in zip(px(x), py(y), ok):
            if good:
                current.append(f"{xi:.1f},{yi:.1f}")
            elif current:
                runs.append(current)
                current = []
        if current:
            runs.append(current)
        for run in runs:
            if len(run) == 1:
                cx, cy = run[0].split(",")
                out.append(f'<circle cx="{cx}" cy="{cy}" r="1.5" fill="{colour}"/>')
            else:
                out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="1.3" points="{" ".join(run)}"/>')
        out.append(f'<rect x="{legend_x}" y="10" width="10" height="3" fill="{colour}"/>'
                   f'<text x="{legend_x + 14}" y="15">{escape(label)}</text>')
        legend_x += 24 + 7 * len(label)
    out.append("</svg>")
    return "\n".join(out)
