"""The headless review report: one self-contained HTML page per clip, written beside the .blend.

It says what an animator needs to decide whether to open the scene at all: the warnings and
self-check flags, the per-frame reprojection residual (with the frames marked as problems), the camera's
pan, tilt, roll and focal length per frame (camera spells shaded), and the proportions against the
average adult's, and with footage, frames of it with the tracks and the solved skeleton drawn on them
(:mod:`.footage_sheet`).  Plots are inline SVG and pictures inline PNG, so the page needs no other file and
no network.
"""

from __future__ import annotations

from html import escape

import numpy as np
from scipy.spatial.transform import Rotation

from ..camera import rotation_matrix
from ..io.file_io import write_atomic
from ..result import Estimate
from ..self_check.checks import SelfCheckSettings, adult_share_ratios
from ..skeleton import CLASSES
from .footage_sheet import pictures_html
from .problems import POOR_FIT, REJECTED, SWAPPED, poor_fit_limit_px, problem_masks, reprojection_series
from .svg_plot import line_plot

#: A class whose share is within these multiples of the average adult's reads "typical".
TYPICAL_RATIO = (0.8, 1.25)
_SPELL_COLOUR = {"still": None, "pan": "#e8f0ff", "tilt": "#eaf8ea", "zoom": "#fff4e0"}


def pan_tilt_roll_deg(est: Estimate) -> np.ndarray:
    """(F, 3) pan, tilt, roll in degrees per frame (the inverse of ``core.camera.pan_tilt_roll_matrix``)."""
    rv = np.array([fr.rotvec_deg for fr in est.frames], dtype=float).reshape(-1, 3)
    if rv.size == 0:
        return np.zeros((0, 3))
    r = rotation_matrix(rv)
    q = Rotation.from_matrix(np.transpose(r, (0, 2, 1)))          # the camera's turn, frame-0 axes
    pan, neg_tilt, roll = np.degrees(q.as_euler("YXZ")).T
    return np.stack([pan, -neg_tilt, roll], axis=1)


def proportion_rows(est: Estimate) -> list[tuple[str, float, float, float, str]]:
    """(class, estimate share, adult share, ratio, verdict) per bone class."""
    adult, ratios = adult_share_ratios(est)
    lo, hi = SelfCheckSettings().proportion_ratio
    rows = []
    for i, name in enumerate(CLASSES):
        share = float(est.proportions[name])
        ratio = float(ratios[i])
        if not (lo <= ratio <= hi):
            verdict = "implausible"
        elif TYPICAL_RATIO[0] <= ratio <= TYPICAL_RATIO[1]:
            verdict = "typical"
        else:
            verdict = "unusual"
        rows.append((name, share, float(adult[i]), ratio, verdict))
    return rows


def _spell_bands(est: Estimate):
    bands = []
    for spell in (est.diagnostics or {}).get("spells") or []:
        try:
            colour = _SPELL_COLOUR.get(str(spell["kind"]), "#f3e8ff")
            if colour:
                bands.append((float(spell["start"]), float(spell["end"]), colour))
        except (KeyError, TypeError, ValueError):
            continue
    return bands


def _problem_text(masks: dict) -> list[str]:
    out = []
    for name, mask in masks.items():
        frames = np.flatnonzero(mask)
        if frames.size:
            shown = ", ".join(str(int(f)) for f in frames[:12]) + (" ..." if frames.size > 12 else "")
            out.append(f"{name}: {frames.size} frame{'s' * (frames.size != 1)} ({shown})")
    return out


def review_html(est: Estimate, *, title: str = "MonoSkel review", fps: float | None = None,
                image_size=None, first_frame: int = 0, pictures=()) -> str:
    """The report page as a string; ``first_frame`` numbers the frames as the scene does; ``pictures``
    (:class:`.footage_sheet.Picture`) are frames of the footage, shown after the warnings."""
    diag = est.diagnostics or {}
    n = len(est.frames)
    frames = np.arange(n) + first_frame
    warnings = [str(w) for w in diag.get("warnings", [])]
    flags = [f.get("message", f.get("code", "")) for f in (diag.get("self_check") or {}).get("flags", [])]
    facts = [("method", est.method), ("frames", str(n)),
             ("focal length", f"{est.focal_mm:.1f} mm (36 mm film)")]
    if fps:
        facts.append(("frame rate", f"{fps:g} fps"))
    if image_size:
        facts.append(("image", f"{int(image_size[0])} x {int(image_size[1])} px"))
    if est.height_m:
        facts.append(("height", f"{est.height_m:.2f} m"))
    if diag.get("spells"):
        facts.append(("camera spells", "; ".join(f"{s.get('start')}-{s.get('end')} {s.get('kind')}"
                                                 for s in diag["spells"] if isinstance(s, dict))))

    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{escape(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:780px;margin:1em auto;color:#222}"
             "table{border-collapse:collapse}td,th{padding:2px 10px;text-align:right}"
             "td:first-child,th:first-child{text-align:left}tr:nth-child(even){background:#f6f6f6}"
             ".warn{color:#a40}.ok{color:#262}.implausible{color:#c00;font-weight:bold}"
             ".unusual{color:#a60}</style></head><body>",
             f"<h1>{escape(title)}</h1><table>"]
    parts += [f"<tr><td>{escape(k)}</td><td style='text-align:left'>{escape(v)}</td></tr>" for k, v in facts]
    parts.append("</table><h2>Warnings</h2>")
    said = warnings + [f for f in flags if f not in warnings]
    if said:
        parts.append("<ul>" + "".join(f"<li class='warn'>{escape(w)}</li>" for w in said) + "</ul>")
    else:
        parts.append("<p class='ok'>No warnings: the self-checks passed.</p>")

    # the animator's own corrections (Flip Bone Depth, Plant Foot): the poses on those frames are no longer the solve's
    by_hand = [f"the bone ending at {escape(str(f.get('bone')))} turned to its other side in depth on frames "
               f"{int(f.get('first', 0)) + first_frame}-{int(f.get('last', 0)) + first_frame} "
               f"({int(f.get('frames', 0))} flipped)" for f in diag.get("depth_flips", []) if isinstance(f, dict)]
    by_hand += [f"the {'left' if f.get('foot') == 'l' else 'right'} foot held still on frames "
                f"{int(f.get('first', 0)) + first_frame}-{int(f.get('last', 0)) + first_frame} "
                f"(it had strayed up to {100 * float(f.get('slide_m', 0.0)):.0f} cm)"
                for f in diag.get("planted_feet", []) if isinstance(f, dict)]
    if by_hand:
        parts.append("<h2>Corrected by hand</h2><ul>" + "".join(f"<li>{line}</li>" for line in by_hand) + "</ul>")

    parts.append(pictures_html(list(pictures), first_frame))

    rep = reprojection_series(est)
    limit = poor_fit_limit_px(est)
    masks = problem_masks(est)
    parts.append("<h2>Fit per frame</h2>")
    if np.isfinite(rep).any():
        marks = []
        for name, colour in ((REJECTED, "#c60"), (SWAPPED, "#909"), (POOR_FIT, "#c00")):
            y = np.where(masks[name], rep, np.nan)
            if np.isfinite(y).any():
                marks.append((name, frames, y, colour))
        parts.append(line_plot([("mean reprojection error", frames, rep, "#1f5fbf")] + marks,
                               title="Reprojection residual", x_label="frame", y_label="pixels",
                               hlines=[] if limit is None else [(limit, f"poor fit > {limit:.1f} px", "#c00")]))
    else:
        parts.append("<p>This estimate has no per-frame reprojection errors.</p>")
    problems = _problem_text(masks)
    if problems:
        parts.append("<ul>" + "".join(f"<li>{escape(p)}</li>" for p in problems) + "</ul>")

    angles = pan_tilt_roll_deg(est)
    focal = np.array([fr.focal_mm for fr in est.frames], dtype=float)
    bands = _spell_bands(est)
    parts.append("<h2>Camera</h2>")
    parts.append(line_plot([("pan", frames, angles[:, 0], "#1f5fbf"), ("tilt", frames, angles[:, 1], "#2a9d3a"),
                            ("roll", frames, angles[:, 2], "#b03030")],
                           title="Camera angles (from frame 0)", x_label="frame", y_label="degrees", bands=bands))
    parts.append(line_plot([("focal length", frames, focal, "#805020")], title="Focal length",
                           x_label="frame", y_label="mm (36 mm film)", bands=bands))

    parts.append("<h2>Proportions against the average adult</h2><table><tr><th>bone class</th>"
                 "<th>share of height</th><th>adult</th><th>ratio</th><th></th></tr>")
    for name, share, adult, ratio, verdict in proportion_rows(est):
        parts.append(f"<tr><td>{escape(name.replace('_', ' '))}</td><td>{share:.4f}</td><td>{adult:.4f}</td>"
                     f"<td>{ratio:.2f}</td><td class='{verdict}'>{verdict}</td></tr>")
    parts.append("</table><p style='font-size:small'>Adult: the built-in average figure's shares; a share "
                 f"{TYPICAL_RATIO[0]}-{TYPICAL_RATIO[1]} times it reads typical, outside the self-check's "
                 "plausible range implausible.</p></body></html>")
    return "\n".join(parts)


def write_review_html(path: str, est: Estimate, **kwargs) -> str:
    """Write :func:`review_html` to ``path`` (atomically) and return the path."""
    write_atomic(path, review_html(est, **kwargs), what="review report")
    return path
