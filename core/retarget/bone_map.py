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


class BoneMapHierarchyError(BoneMapError):
    """The mapped bones do not hang from one another as a body does (a generated Rigify rig's controls
    hang from mechanism bones): such a rig can still be driven, by evaluating it."""


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


def _guess_by_shape(rig: TargetRig) -> dict[str, int]:
    """role -> bone from the tree's shape alone (for rigs named "Bone", "Bone.001", ...).

    The hips are the first bone, from the root, where three long branches start (two legs going
    down, the spine going up); up is the rig's tallest axis, its sign the spine's side; the chest is
    where two more long branches (the arms) leave the spine; each limb follows the path to its
    farthest end, its upper bone being the longest of the first ones; left is ``up x forward``, forward
    being where the toes point (+X, Blender's convention, when the feet do not say).
    """
    keep = [i for i in range(rig.n) if not _is_helper(rig.names[i])]
    if len(keep) < 10:
        return {}
    kept = set(keep)
    pts = np.concatenate([rig.head[keep], rig.tail[keep]])
    axis = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
    height = float(pts[:, axis].max() - pts[:, axis].min())
    children = {i: [c for c in rig.children(i) if c in kept] for i in keep}

    def farthest_path(i, key):
        """Bones from ``i`` to the leaf of its subtree that maximises ``key(leaf)``."""
        best, stack = None, [[i]]
        while stack:
            path = stack.pop()
            kids = children[path[-1]]
            if not kids:
                if best is None or key(path[-1]) > key(best[-1]):
                    best = path
            stack.extend(path + [c] for c in kids)
        return best

    def subtree(i):
        out, stack = [], [i]
        while stack:
            j = stack.pop()
            out.append(j)
            stack.extend(children[j])
        return out

    def reach(i):
        return max(np.linalg.norm(rig.tail[j] - rig.head[i]) for j in subtree(i))

    def long_branches(i):
        return [c for c in children[i] if reach(c) >= 0.15 * height]

    hips = next((i for i in keep if len(long_branches(i)) >= 3), None)
    if hips is None:
        return {}
    branches = long_branches(hips)
    side = [float(np.mean([rig.tail[j][axis] for j in subtree(c)]) - rig.head[hips][axis]) for c in branches]
    sign = 1.0 if sum(v > 0 for v in side) <= 1 else -1.0        # one branch up (spine), the rest down
    order = np.argsort([-sign * v for v in side])
    spine, legs = branches[order[0]], [branches[k] for k in order[1:3]]
    up = sign

    def upper_of(path, first):
        """(index in path of the limb's upper bone: the longest among the first ``first`` bones)."""
        lengths = [rig.length(j) for j in path[:first]]
        return int(np.argmax(lengths))

    out: dict[str, int] = {"hips": hips}
    lateral = [k for k in range(3) if k != axis]
    leg_heads = np.array([rig.head[c] for c in legs])
    lat = lateral[int(np.argmax(np.abs(leg_heads[0, lateral] - leg_heads[1, lateral])))]
    leg_paths = []
    for c in legs:
        path = farthest_path(c, lambda j: -up * rig.tail[j][axis])
        leg_paths.append((path, upper_of(path, 2)))
    # left: +X (Blender's convention) unless the feet say which way the rig faces (toes point forward)
    up_vec = np.zeros(3)
    up_vec[axis] = up
    toes = [rig.tail[p[-1]] - rig.head[p[k + 2]] for p, k in leg_paths if len(p) > k + 2]
    left_sign = 1.0
    if toes:
        forward = np.mean(toes, axis=0)
        forward[axis] = 0.0
        if np.linalg.norm(forward) > 0.02 * height:
            left = np.cross(up_vec, forward / np.linalg.norm(forward))
            if abs(left[lat]) > 0.5:
                left_sign = float(np.sign(left[lat]))
    for path, k in leg_paths:
        s = "L" if left_sign * (rig.head[path[k]][lat] - rig.head[hips][lat]) > 0 else "R"
        for role, j in zip(("thigh", "shin", "foot", "toe"), path[k:k + 4]):
            out[f"{role}.{s}"] = j
    top = farthest_path(spine, lambda j: up * rig.tail[j][axis])
    for n, bone in enumerate(top):
        arms = [c for c in long_branches(bone) if c not in top]
        if len(arms) >= 2:
            out["chest"] = bone
            # the head starts below the crown; a bone that starts at the crown is a head-end marker
            crown = max(up * rig.tail[j][axis] for j in top)
            rest = [j for j in top[n + 1:] if up * rig.head[j][axis] < crown - 0.05 * height]
            if rest:
                out["head"] = rest[-1]
            for c in arms[:2]:
                path = farthest_path(c, lambda j, base=rig.head[bone]: np.linalg.norm(rig.tail[j] - base))
                k = upper_of(path, 3)
                s = "L" if left_sign * (rig.tail[path[k]][lat] - rig.head[bone][lat]) > 0 else "R"
                if k > 0:
                    out[f"clavicle.{s}"] = path[k - 1]
                for role, j in zip(("upper_arm", "forearm", "hand"), path[k:k + 3]):
                    out[f"{role}.{s}"] = j
            break
    return out


def guess_bone_map(rig: TargetRig) -> dict[str, str]:
    """role -> bone name for every role the rig's names and shape decide (check it with
    :func:`check_bone_map`; missing required roles raise there, not here).  Names first; the
    tree's shape fills what names leave open (:func:`_guess_by_shape`)."""
    named = _guess_by_names(rig)
    if all(r in named for r in REQUIRED):
        return named
    shaped = {r: rig.names[i] for r, i in _guess_by_shape(rig).items()}
    used = set(named.values())
    return {**{r: b for r, b in shaped.items() if b not in used}, **named}


def _guess_by_names(rig: TargetRig) -> dict[str, str]:
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
            raise BoneMapHierarchyError(f"{lower} ({rig.names[out[lower]]}) must hang below {upper} "
                               f"({rig.names[out[upper]]}) in the rig's hierarchy")
    return out
