"""Command-line options the benches share: another pose prior or pose lifter file in place of the shipped
ones, and the joint solve's settings (its lifter's, its reprojection sigma), so that every bench measures a
candidate the same way.

    add_model_arguments(parser, joint_solve=True)   # --prior, --lifter (a file or 'none'), --solve-cue, --cue-sigma,
                                                    # --reproj-px
    apply_model_arguments(parser.parse_args())
"""

from __future__ import annotations


def add_model_arguments(ap, *, joint_solve: bool) -> None:
    """``--prior FILE`` and ``--lifter FILE`` always; with ``joint_solve`` also ``--lifter none`` (the joint
    solve without the lifter), ``--solve-cue`` and ``--cue-sigma``."""
    ap.add_argument("--prior", default=None, help="a pose prior file instead of the shipped one")
    if not joint_solve:
        ap.add_argument("--lifter", default=None, help="a pose lifter file instead of the shipped one")
        return
    ap.add_argument("--lifter", default=None, help="a pose lifter file instead of the shipped one, or 'none'")
    ap.add_argument("--video-lifter", default=None,
                    help="a lifter file for consecutive frames (the joint solve's) instead of the shipped one, "
                         "or 'single': the single-picture lifter there too")
    ap.add_argument("--solve-cue", type=float, default=None,
                    help="core.joint_solve.pipeline.SOLVE_CUE_SIGMA (0: the lifter's cue not in the solve)")
    ap.add_argument("--cue-sigma", type=float, default=None, help="core.joint_solve.signs_dp.SIGMA_CUE")
    ap.add_argument("--reproj-px", type=float, default=None,
                    help="the joint solve's reprojection sigma, pixels (core.joint_solve.solver.Sigmas.reproj_px; "
                         "a background point's scales with it)")


def apply_model_arguments(args) -> None:
    """Set what :func:`add_model_arguments`' options ask for (module settings, for this process)."""
    import core.motion_prior as mp

    if args.prior is not None:
        mp.DEFAULT_PATH = args.prior
        mp.load_default.cache_clear()
    if args.lifter == "none":
        from core.joint_solve import pipeline

        pipeline.USE_POSE_LIFTER = False
    elif args.lifter is not None:
        mp.DEFAULT_LIFTER_PATH = args.lifter
        mp.load_default_lifter.cache_clear()
        mp.load_video_lifter.cache_clear()
    if getattr(args, "video_lifter", None) is not None:
        mp.DEFAULT_VIDEO_LIFTER_PATH = "" if args.video_lifter == "single" else args.video_lifter
        mp.load_video_lifter.cache_clear()
    if getattr(args, "solve_cue", None) is not None:
        from core.joint_solve import pipeline

        pipeline.SOLVE_CUE_SIGMA = args.solve_cue or None
    if getattr(args, "cue_sigma", None) is not None:
        from core.joint_solve import signs_dp

        signs_dp.SIGMA_CUE = args.cue_sigma
    if getattr(args, "reproj_px", None) is not None:
        _set_reprojection_sigma(args.reproj_px)


def _set_reprojection_sigma(px: float) -> None:
    """Every joint solve of this process weighs the tracks with ``px`` pixels' sigma (a background point's
    sigma scaled by the same factor)."""
    import dataclasses

    from core.joint_solve import pipeline

    if not px > 0:
        raise SystemExit(f"--reproj-px must be a positive number of pixels, got {px}")
    shipped = pipeline._sigmas

    def sigmas(static):
        s = shipped(static)
        return dataclasses.replace(s, reproj_px=px, static_px=s.static_px * px / s.reproj_px)

    pipeline._sigmas = sigmas
