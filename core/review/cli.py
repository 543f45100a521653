"""``python -m core report RESULT.json --out REPORT.html``: the headless review page of an estimate."""

from __future__ import annotations

import os

from ..io.file_io import check_output_file
from .report import write_review_html


def add_arguments(parser) -> None:
    parser.add_argument("estimate", metavar="RESULT.json", help="a skeleton-estimate JSON (python -m core estimate)")
    parser.add_argument("--out", "-o", metavar="REPORT.html", help="where to write the page (default: beside "
                        "RESULT.json, RESULT.review.html)")
    parser.add_argument("--title", help="the page's title (default: the estimate's file name)")
    parser.add_argument("--first-frame", type=int, default=0,
                        help="number of the clip's first frame in the plots (default 0; the .blend uses 1)")


def run(args) -> int:
    from ..result import read_estimate_json

    out = check_output_file(args.out or os.path.splitext(args.estimate)[0] + ".review.html")
    est = read_estimate_json(args.estimate)
    diag = est.diagnostics or {}
    fps = diag.get("fps") if isinstance(diag.get("fps"), (int, float)) else None
    size = diag.get("image_size") if isinstance(diag.get("image_size"), (list, tuple)) else None
    write_review_html(out, est, title=args.title or f"MonoSkel review: {os.path.basename(args.estimate)}",
                      fps=fps, image_size=size, first_frame=args.first_frame)
    print(f"wrote {out}")
    return 0
