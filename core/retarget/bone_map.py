"""Which bone of the target rig plays which part: guessed from names, completed from the chains' shape.

Names decide the limbs, in the spellings of the rigs animators use: Rigify (``upper_arm.L``,
``thigh_fk.L``), Mixamo (``mixamorig:LeftForeArm``, ``LeftUpLeg``), Unreal's mannequin (``upperarm_l``,
``calf_r``) and most hand-made rigs (``Arm.L``, ``shin_R``, ``LeftShin``).  Control and helper bones
(IK, MCH, ORG, DEF, tweak, pole, twist, roll, parent ...) are never chosen, so a generated Rigify rig maps
onto its FK controls.  The shape decides the rest: the **hips** are the nearest common ancestor of the
two thighs, the **chest** that of the two clavicles (or upper arms), the **spine** bones are those
between them and the **neck** bones those between chest and head.  Fingers, twist bones and anything
else unmapped are left alone by the retargeting.
"""

from __future__ import annotations

import re

import numpy as np

from .rig import TargetRig

SIDES = ("L", "R")
LIMB_PARTS = ("clavicle", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toe")
#: Every role of a bone map, in the order the sidebar shows them.
ROLES: tuple[str, ...] = ("hips", "chest", "head") + tuple(f"{p}.{s}" for s in SIDES for p in LIMB_PARTS)
REQUIRED: tuple[str, ...] = ("hips", "chest", "head") + tuple(
    f"{p}.{s}" for s in SIDES for p in ("upper_arm", "forearm", "thigh", "shin"))

#: Body words (side removed, words joined) of each limb part.
_PART_WORDS = {
    "clavicle": {"shoulder", "clavicle", "collar", "collarbone"},
    "upper_arm": {"upperarm", "arm", "uparm", "bicep"},
    "forearm": {"forearm", "lowerarm", "loarm", "elbow"},
    "hand": {"hand", "wrist"},
    "thigh": {"thigh", "upleg", "upperleg", "femur"},
    "shin": {"shin", "calf", "leg", "lowerleg", "loleg", "knee"},
    "foot": {"foot", "ankle"},
    "toe": {"toe", "toebase", "ball", "toes"},
}
_HEAD_WORDS = {"head"}
#: Words that mark control and helper bones (never mapped); "fk" is dropped instead, so FK controls map.
_HELPER_WORDS = {"ik", "mch", "org", "def", "tweak", "pole", "target", "twist", "roll", "parent", "socket",
                 "prop", "vis", "master", "root", "ctrl", "helper", "end", "nub", "tip", "jnt"}
_LEFT, _RIGHT = {"l", "left", "lft"}, {"r", "right", "rgt", "rt"}


class BoneMapError(ValueError):
    """A bone map that cannot drive the rig: one sentence naming the role and the bone."""


def words(name: str) -> list[str]:
    """Lower-case words of a bone name: namespace dropped, split at separators, digits and camelCase."""
    name = name.rsplit(":", 1)[-1]
    name = re.sub(r"([a-z])([A-Z])", r"\1 \2", name)
    return [w for w in re.split(r"[^A-Za-z]+", name.lower()) if w]


def _side_and_body(name: str) -> tuple[str | None, str, set]:
    ws = words(name)
    side = None
    body = []
    for w in ws:
        if w in _LEFT and side is None:
            side = "L"
        elif w in _RIGHT and side is None:
            side = "R"
        elif w != "fk":
            body.append(w)
    return side, "".join(body), set(body)


def _is_helper(name: str) -> bool:
    return bool(set(words(name)) & _HELPER_WORDS)


def _candidates(rig: TargetRig) -> dict[str, list[int]]:
    """role -> bones whose name says that role (parents first)."""
    found: dict[str, list[int]] = {}
    for i, name in enumerate(rig.names):
        side, body, body_words = _side_and_body(name)
        if body_words & _HELPER_WORDS or not body:
            continue
        if body in _HEAD_WORDS and side is None:
            found.setdefault("head", []).append(i)
            continue
        for part, vocabulary in _PART_WORDS.items():
            if body in vocabulary and side is not None:
                found.setdefault(f"{part}.{side}", []).append(i)
    return found


def _common_ancestor(rig: TargetRig, a: int, b: int) -> int | None:
    up = set([a] + rig.ancestors(a))
    for c in [b] + rig.ancestors(b):
        if c in up:
            return c
    return None


def _is_below(rig: TargetRig, child: int, ancestor: int) -> bool:
    return ancestor in rig.ancestors(child)


def guess_bone_map(rig: TargetRig) -> dict[str, str]:
    """role -> bone name for every role the rig's names and shape decide (check it with
    :func:`check_bone_map`; missing required roles raise there, not here)."""
    cands = _candidates(rig)
    chosen: dict[str, int] = {}

    def pick(role, below=None, above=None):
        for i in cands.get(role, []):
            if below is not None and not _is_below(rig, i, below):
                continue
            if above is not None and not _is_below(rig, above, i):
                continue
            chosen[role] = i
            return i
        return None

    for s in SIDES:
        arm = pick(f"upper_arm.{s}")
        if arm is not None:
            pick(f"forearm.{s}", below=arm)
            if f"forearm.{s}" in chosen:
                pick(f"hand.{s}", below=chosen[f"forearm.{s}"])
            pick(f"clavicle.{s}", above=arm)
        thigh = pick(f"thigh.{s}")
        if thigh is not None:
            pick(f"shin.{s}", below=thigh)
            if f"shin.{s}" in chosen:
                pick(f"foot.{s}", below=chosen[f"shin.{s}"])
                if f"foot.{s}" in chosen:
                    pick(f"toe.{s}", below=chosen[f"foot.{s}"])
    if "thigh.L" in chosen and "thigh.R" in chosen:
        hips = _common_ancestor(rig, chosen["thigh.L"], chosen["thigh.R"])
        if hips is not None and not _is_helper(rig.names[hips]):
            chosen["hips"] = hips
        elif "torso" in rig.index:          # a generated Rigify rig: the torso control carries the body
            chosen["hips"] = rig.index["torso"]
    pair = [chosen.get(f"clavicle.{s}", chosen.get(f"upper_arm.{s}")) for s in SIDES]
    if None not in pair:
        chest = _common_ancestor(rig, pair[0], pair[1])
        if chest is not None and _is_helper(rig.names[chest]) and "chest" in rig.index:
            chosen["chest"] = rig.index["chest"]      # a generated Rigify rig: controls, not the chain
            pick("head")
            for s in SIDES:
                if f"clavicle.{s}" not in chosen:
                    pick(f"clavicle.{s}")
        elif chest is not None and chest not in pair:
            chosen["chest"] = chest
            for s in SIDES:       # a bone between chest and upper arm is the clavicle, whatever its name
                arm = chosen.get(f"upper_arm.{s}")
                if f"clavicle.{s}" not in chosen and arm is not None and int(rig.parents[arm]) not in (chest, -1):
                    chosen[f"clavicle.{s}"] = int(rig.parents[arm])
            pick("head", below=chest)
            if "head" not in chosen:
                top = _top_of_chain(rig, chest, exclude=set(chosen.values()))
                if top is not None:
                    chosen["head"] = top
    return {role: rig.names[i] for role, i in chosen.items()}


def _top_of_chain(rig: TargetRig, chest: int, exclude: set) -> int | None:
    """The head of a rig without a bone named so: from the chest, follow the child that continues
    upward from its parent's tail (neck bones, then the head) until none does."""
    up = rig.tail[chest] - rig.head[chest]
    up = up / max(float(rig.length(chest)), 1e-12)
    current, top = chest, None
    while True:
        best, best_dot = None, 0.5
        for c in rig.children(current):
            if c in exclude:
                continue
            d = rig.tail[c] - rig.head[c]
            dot = float(d @ up) / max(rig.length(c), 1e-12)
            near = np.linalg.norm(rig.head[c] - rig.tail[current]) <= 0.25 * max(rig.length(current), 1e-12)
            if near and dot > best_dot:
                best, best_dot = c, dot
        if best is None:
            return top
        current = top = best


def chain_between(rig: TargetRig, low: int, high: int) -> list[int]:
    """Bones strictly between ``low`` (an ancestor) and ``high``, lowest first."""
    out = []
    for a in rig.ancestors(high):
        if a == low:
            return out[::-1]
        out.append(a)
    raise BoneMapError(f"{rig.names[high]!r} is not below {rig.names[low]!r}")


def role_parent(role: str, mapped) -> str | None:
    """The role a role hangs from in a body, whatever the rig's own hierarchy (None for the hips)."""
    if role == "hips":
        return None
    if role in ("chest",) or role.startswith("thigh."):
        return "hips"
    if role == "head" or role.startswith("clavicle."):
        return "chest"
    part, side = role.split(".")
    up = {"upper_arm": "clavicle", "forearm": "upper_arm", "hand": "forearm", "shin": "thigh", "foot": "shin",
          "toe": "foot"}[part]
    if up == "clavicle" and f"clavicle.{side}" not in mapped:
        return "chest"
    return f"{up}.{side}"


def logical_rig(rig: TargetRig, bone_map: dict[str, str]) -> TargetRig:
    """The mapped bones alone, each hanging from the bone of its body parent (:func:`role_parent`).

    For rigs whose controls hang from constraint-driven mechanism bones (a generated Rigify rig): the
    solve runs on this body, and the result is applied by evaluating the real rig.
    """
    mapped = {r: b for r, b in bone_map.items() if b}
    order = [r for r in ROLES if r in mapped]
    names = [mapped[r] for r in order]
    for n in names:
        if n not in rig.index:
            raise BoneMapError(f"the rig has no bone {n!r}")
    parents = []
    for r in order:
        up = role_parent(r, mapped)
        while up is not None and up not in mapped:
            up = role_parent(up, mapped)
        parents.append(-1 if up is None else order.index(up))
    idx = [rig.index[n] for n in names]
    return TargetRig(names, parents, rig.head[idx], rig.tail[idx], rig.rest[idx])


def check_bone_map(rig: TargetRig, bone_map: dict[str, str]) -> dict[str, int]:
    """role -> bone index, after checking every bone exists and the chains make a body."""
    out: dict[str, int] = {}
    for role, name in bone_map.items():
        if role not in ROLES:
            raise BoneMapError(f"unknown role {role!r}; roles are {', '.join(ROLES)}")
        if not name:
            continue
        if name not in rig.index:
            raise BoneMapError(f"{role}: the rig has no bone {name!r}")
        out[role] = rig.index[name]
    if len(set(out.values())) != len(out):
        twice = [name for name in set(bone_map.values()) if name and list(bone_map.values()).count(name) > 1]
        raise BoneMapError(f"{twice[0]!r} is mapped to two roles")
    missing = [r for r in REQUIRED if r not in out]
    if missing:
        raise BoneMapError("no bone mapped for " + ", ".join(missing) + ": pick them in the bone map")
    order = [("hips", "chest"), ("chest", "head")]
    for s in SIDES:
        order += [("hips", f"thigh.{s}"), (f"thigh.{s}", f"shin.{s}"), (f"shin.{s}", f"foot.{s}"),
                  (f"foot.{s}", f"toe.{s}"), ("chest", f"clavicle.{s}"), (f"clavicle.{s}", f"upper_arm.{s}"),
                  ("chest", f"upper_arm.{s}"), (f"upper_arm.{s}", f"forearm.{s}"), (f"forearm.{s}", f"hand.{s}")]
    for upper, lower in order:
        if upper in out and lower in out and not _is_below(rig, out[lower], out[upper]):
            raise BoneMapError(f"{lower} ({rig.names[out[lower]]}) must hang below {upper} "
                               f"({rig.names[out[upper]]}) in the rig's hierarchy")
    return out
