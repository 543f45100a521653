"""Command-line options the benches share: another pose prior or pose lifter file in place of the shipped
ones, and the joint solve's lifter settings, so that every bench measures a candidate the same way.

    add_model_arguments(parser, joint_solve=True)   # --prior, --lifter (a file or 'none'), --solve-cue, --cue-sigma
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
