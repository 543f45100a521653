"""What a detector's tracks show of its own errors, with no ground truth.

Real footage has no 3D truth, but the 2D tracks still tell how the detector
behaved:

* **jitter**: frame-to-frame motion of each joint while the person holds
  still (the torso and the limbs' centre move under 2 % of the torso's length
  per frame), in pixels and in torso lengths;
* **left/right swaps**: a limb pair whose two joints fit the previous frame
  better exchanged than as labelled (both joints apart by a tenth of a torso
  or more, so crossing legs do not count);
* **drop-outs**: a joint unseen (missing or confidence under 0.5) while the
  person is found, as runs in seconds;
* **person switches**: the torso jumping to someone else
  (:func:`core.track_cleaning.people.person_switches`);
* the found share and the longest stretch of one person.

Units are body- and time-relative so clips at any size and frame rate compare.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..runs import runs
from ..skeleton import JOINT_INDEX, JOINTS, LIMB_PAIRS
from ..track_cleaning.people import longest_one_person_stretch, person_switches
from ..tracks import Tracks

SEEN_CONF = 0.5
STILL_TORSO = 0.02      # torso lengths per frame
SWAP_MIN_GAP = 0.1      # torso lengths between the pair's joints

_PELVIS, _THORAX = JOINT_INDEX["pelvis"], JOINT_INDEX["thorax"]


def track_quality(tracks: Tracks) -> dict:
    """The detector's measurable errors in ``tracks`` (a dict of plain numbers, JSON-ready)."""
    xy = np.asarray(tracks.xy, dtype=float)
    conf = np.asarray(tracks.conf, dtype=float)
    n = xy.shape[0]
    fps = float(tracks.fps)
    seen = np.isfinite(xy).all(-1) & (conf >= SEEN_CONF)
    found = np.isfinite(xy[:, [_PELVIS, _THORAX]]).all((1, 2))
    torso = np.linalg.norm(xy[:, _THORAX] - xy[:, _PELVIS], axis=-1)
    scale = float(np.nanmedian(torso[found])) if found.any() else float("nan")

    local = np.maximum(torso[1:], torso[:-1])[:, None]                         # people near and far differ
    step = np.linalg.norm(np.diff(xy, axis=0), axis=-1) / local                # (n-1, 17) torso lengths
    pair_found = found[1:] & found[:-1]
    jump = np.where(pair_found, step[:, _PELVIS], 0.0)
    switches = person_switches(xy)
    start, end = longest_one_person_stretch(switches, found)

    with warnings.catch_warnings():    # frames with no joint seen twice give NaN, as they should
        warnings.simplefilter("ignore", RuntimeWarning)
        body_step = np.nanmedian(np.where(seen[1:] & seen[:-1], step, np.nan), axis=1)
    still = pair_found & (jump <= STILL_TORSO) & (body_step <= STILL_TORSO)
    jitter = {}
    for j, name in enumerate(JOINTS):
        held = still & seen[1:, j] & seen[:-1, j]
        d = step[held, j]
        px = d * local[held, 0]
        if d.size >= 5:
            jitter[name] = {"median_px": float(np.median(px)), "median_torso": float(np.median(d)),
                            "p95_px": float(np.percentile(px, 95)), "frames": int(d.size)}

    swaps = {}
    for left, right in LIMB_PAIRS.values():
        for a, b in zip(left, right):
            both = seen[1:, a] & seen[1:, b] & seen[:-1, a] & seen[:-1, b] & pair_found
            gap = np.linalg.norm(xy[1:, a] - xy[1:, b], axis=-1) / local[:, 0]
            kept = (np.linalg.norm(xy[1:, a] - xy[:-1, a], axis=-1) + np.linalg.norm(xy[1:, b] - xy[:-1, b], axis=-1))
            crossed = (np.linalg.norm(xy[1:, a] - xy[:-1, b], axis=-1)
                       + np.linalg.norm(xy[1:, b] - xy[:-1, a], axis=-1))
            ok = both & (gap >= SWAP_MIN_GAP)
            ok[switches - 1] = False
            flips = ok & (crossed < 0.5 * kept)
            name = JOINTS[a][2:]
            swaps[name] = {"flips": int(flips.sum()), "pairs": int(ok.sum()),
                           "rate": float(flips.sum() / max(1, ok.sum()))}

    dropouts = {}
    for j, name in enumerate(JOINTS):
        lost = found & ~seen[:, j]
        spans = [(e - s) / fps for s, e in runs(lost)]
        dropouts[name] = {"share": float(lost.sum() / max(1, found.sum())), "runs": len(spans),
                          "longest_s": float(max(spans, default=0.0))}

    return {"frames": int(n), "fps": fps, "found_share": float(found.mean()) if n else 0.0,
            "torso_px": scale, "person_switches": int(switches.size), "switch_frames": switches.tolist(),
            "longest_stretch": {"start": int(start), "frames": int(end - start), "seconds": (end - start) / fps},
            "still_frames": int(still.sum()), "jitter": jitter, "swaps": swaps, "dropouts": dropouts}
