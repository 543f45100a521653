"""``OUT/index.html``: every shot of a folder run, its status, warnings, main figures and review page.

Built from what is on disk (each shot's status record and result JSON), so it is the same whether the
shots were built here in one run, over several runs, or as tasks on a farm.  ``OUT/index.json`` holds the
same rows for scripts.
"""

from __future__ import annotations

import json
import os
import statistics
from html import escape

from ..io.file_io import write_atomic
from .discover import Shot
from .outputs import FAILED, OK, read_status, shot_outputs

BUILT, UP_TO_DATE, NOT_RUN = "built", "up to date", "not run"


def result_figures(path: str) -> dict:
    """The estimate's main figures and warnings from its result JSON ({} when unreadable)."""
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError):
        return {}
    if not isinstance(doc, dict):
        return {}
    diag = doc.get("diagnostics") if isinstance(doc.get("diagnostics"), dict) else {}
    frames = doc.get("frames") if isinstance(doc.get("frames"), list) else []
    fits = [f.get("reprojection_px") for f in frames if isinstance(f, dict)]
    fits = [float(v) for v in fits if isinstance(v, (int, float))]
    warnings = [str(w) for w in diag.get("warnings") or []]
    for flag in (diag.get("self_check") or {}).get("flags") or []:
        text = str(flag.get("message", flag.get("code", ""))) if isinstance(flag, dict) else str(flag)
        if text and text not in warnings:
            warnings.append(text)
    return {"method": doc.get("method"), "frames": len(frames), "focal_mm": doc.get("focal_mm"),
            "height_m": doc.get("height_m"), "median_fit_px": statistics.median(fits) if fits else None,
            "warnings": warnings}


def shot_row(shot: Shot, out_dir: str, this_run: dict) -> dict:
    """One shot's row: status (``this_run`` maps names to BUILT / UP_TO_DATE for this run) and figures."""
    outs = shot_outputs(out_dir, shot)
    status = read_status(outs) or {}
    state = status.get("status")
    row = {"shot": shot.name, "input": shot.path, "kind": shot.kind,
           "status": state if state in (OK, FAILED) else NOT_RUN, "this_run": this_run.get(shot.name, ""),
           "error": status.get("error", ""), "seconds": status.get("seconds"),
           "peak_rss_mb": status.get("peak_rss_mb"), "finished": status.get("finished", "")}
    if state == OK:
        row.update(result_figures(outs.result))
    for key, path in (("review", outs.review), ("blend", outs.blend), ("log", outs.log)):
        row[key] = os.path.relpath(path, out_dir) if os.path.isfile(path) else None
    return row


def _number(value, fmt: str) -> str:
    return format(value, fmt) if isinstance(value, (int, float)) else ""


def index_html(rows: list[dict], title: str) -> str:
    ok = sum(r["status"] == OK for r in rows)
    failed = [r for r in rows if r["status"] == FAILED]
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{escape(title)}</title>",
             "<style>body{font-family:sans-serif;margin:1em auto;max-width:1200px;color:#222}"
             "table{border-collapse:collapse}td,th{padding:3px 8px;text-align:right;vertical-align:top}"
             "td.l,th.l{text-align:left}tr:nth-child(even){background:#f6f6f6}.failed{color:#c00;font-weight:bold}"
             ".ok{color:#262}.error{color:#c00;text-align:left}.warn{color:#a40;font-size:small;text-align:left}.dim{color:#777}</style></head><body>",
             f"<h1>{escape(title)}</h1>",
             f"<p>{len(rows)} shot{'s' * (len(rows) != 1)}: {ok} built, {len(failed)} failed"
             f"{', ' + str(len(rows) - ok - len(failed)) + ' not run' if len(rows) - ok - len(failed) else ''}.</p>",
             "<table><tr><th class='l'>shot</th><th class='l'>status</th><th>frames</th><th class='l'>method</th>"
             "<th>focal mm</th><th>height m</th><th>median fit px</th><th>warnings</th><th>seconds</th>"
             "<th>peak MB</th><th class='l'>files</th></tr>"]
    for r in rows:
        state = r["status"]
        status_text = {OK: "ok", FAILED: "failed"}.get(state, state)
        if r["this_run"] == UP_TO_DATE:
            status_text += " <span class='dim'>(up to date)</span>"
        links = [f"<a href='{escape(r[k])}'>{label}</a>" for k, label in
                 (("review", "review"), ("blend", ".blend"), ("log", "log")) if r.get(k)]
        shot_cell = (f"<a href='{escape(r['review'])}'>{escape(r['shot'])}</a>" if state == OK and r.get("review")
                     else escape(r["shot"]))
        warnings = r.get("warnings") or []
        parts.append(
            f"<tr><td class='l' title='{escape(r['input'])}'>{shot_cell}</td>"
            f"<td class='l {escape(state.replace(' ', '-'))}'>{status_text}</td>"
            f"<td>{_number(r.get('frames'), 'd')}</td><td class='l'>{escape(str(r.get('method') or ''))}</td>"
            f"<td>{_number(r.get('focal_mm'), '.1f')}</td><td>{_number(r.get('height_m'), '.2f')}</td>"
            f"<td>{_number(r.get('median_fit_px'), '.2f')}</td><td>{len(warnings) if state == OK else ''}</td>"
            f"<td>{_number(r.get('seconds'), '.1f')}</td><td>{_number(r.get('peak_rss_mb'), '.0f')}</td>"
            f"<td class='l'>{' '.join(links)}</td></tr>")
        said = ([r["error"]] if state == FAILED else warnings)
        if said:
            cls = "error" if state == FAILED else "warn"
            parts.append(f"<tr><td></td><td colspan='10' class='{cls}' style='text-align:left'>"
                         + "<br>".join(escape(w) for w in said) + "</td></tr>")
    parts.append("</table><p style='font-size:small'>median fit: the median over frames of the mean reprojection "
                 "error; peak MB: the largest memory the shot's process used.</p></body></html>")
    return "\n".join(parts)


def write_index(out_dir: str, shots: list[Shot], this_run: dict | None = None,
                title: str = "MonoSkel shots") -> list[dict]:
    """Write ``OUT/index.html`` and ``OUT/index.json`` for ``shots``; returns the rows."""
    rows = [shot_row(s, out_dir, this_run or {}) for s in shots]
    write_atomic(os.path.join(out_dir, "index.html"), index_html(rows, title), what="index page")
    write_atomic(os.path.join(out_dir, "index.json"), json.dumps({"format": "monoskel-shot-index", "shots": rows},
                                                                 indent=1), what="index")
    return rows
