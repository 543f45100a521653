"""BVH reader and forward kinematics: channel orders, odd formatting, errors, FK by hand."""

from __future__ import annotations

import numpy as np
import pytest

from core.errors import InputError
from core.io.bvh import format_bvh, make_bvh, parse_bvh, read_bvh, up_axis

# Hand-written rotations by +90 degrees (column vectors), independent of the module's own builder.
RX90 = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)
RY90 = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
RZ90 = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], dtype=float)


def two_bone_text(root_channels: str, frame: str, child_channels: str = "CHANNELS 3 Zrotation Xrotation Yrotation",
                  child_frame: str = "0 0 0") -> str:
    return f"""HIERARCHY
ROOT Hips
{{
  OFFSET 0 0 0
  {root_channels}
  JOINT Chest
  {{
    OFFSET 0 2 0
    {child_channels}
    End Site
    {{
      OFFSET 1 0 0
    }}
  }}
}}
MOTION
Frames: 1
Frame Time: 0.04
{frame} {child_frame}
"""


@pytest.mark.parametrize("order, matrices", [
    ("Xrotation Yrotation Zrotation", (RX90, RY90, RZ90)),
    ("Zrotation Yrotation Xrotation", (RZ90, RY90, RX90)),
    ("Yrotation Zrotation Xrotation", (RY90, RZ90, RX90)),
    ("Zrotation Xrotation Yrotation", (RZ90, RX90, RY90)),
])
def test_channel_order_is_the_matrix_product_order(order, matrices):
    text = two_bone_text(f"CHANNELS 6 Xposition Yposition Zposition {order}", "10 20 30 90 90 90")
    bvh = parse_bvh(text)
    positions = bvh.world_positions()[0]
    rot = matrices[0] @ matrices[1] @ matrices[2]
    chest = np.array([10, 20, 30]) + rot @ np.array([0, 2, 0])
    end = chest + rot @ np.array([1, 0, 0])
    np.testing.assert_allclose(positions[bvh.index("Chest")], chest, atol=1e-12)
    np.testing.assert_allclose(positions[bvh.index("Chest_End")], end, atol=1e-12)


def test_hand_computed_two_level_chain():
    # root turned 90 deg about z; chest turned 90 deg about x in the root's frame
    text = two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                         "1 2 3 90 0 0", child_frame="0 90 0")
    bvh = parse_bvh(text)
    p = bvh.world_positions()[0]
    # chest = root + Rz90 (0,2,0) = (1,2,3) + (-2,0,0)
    np.testing.assert_allclose(p[1], [-1, 2, 3], atol=1e-12)
    # end = chest + Rz90 Rx90 (1,0,0) = chest + Rz90 (1,0,0) = chest + (0,1,0)
    np.testing.assert_allclose(p[2], [-1, 3, 3], atol=1e-12)
    _, rotations = bvh.world_transforms()
    np.testing.assert_allclose(rotations[0, 1], RZ90 @ RX90, atol=1e-12)


def test_position_channels_on_a_child_replace_its_offset():
    text = two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "0 0 0 90 0 0",
                         child_channels="CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                         child_frame="5 0 0 0 0 0")
    p = parse_bvh(text).world_positions()[0]
    np.testing.assert_allclose(p[1], RZ90 @ [5, 0, 0], atol=1e-12)   # offset (0,2,0) ignored, rotated by parent


def test_partial_position_channels_default_to_zero():
    text = two_bone_text("CHANNELS 4 Yposition Zrotation Xrotation Yrotation", "7 0 0 0")
    bvh = parse_bvh(text)
    np.testing.assert_allclose(bvh.world_positions()[0, 0], [0, 7, 0])


def test_root_without_position_channels_uses_offset():
    text = two_bone_text("CHANNELS 3 Zrotation Xrotation Yrotation", "0 0 0").replace("OFFSET 0 0 0", "OFFSET 4 5 6", 1)
    np.testing.assert_allclose(parse_bvh(text).world_positions()[0, 0], [4, 5, 6])


def test_crlf_tabs_blank_lines_and_brace_on_the_joint_line():
    text = two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "0 0 0 0 0 0")
    odd = text.replace("  ", "\t").replace("JOINT Chest\n\t{", "JOINT Chest {").replace("MOTION", "\nMOTION\n")
    odd = odd.replace("Frame Time: 0.04\n", "Frame Time:\t0.04\n\n").replace("\n", "\r\n") + "\r\n\r\n"
    plain, funny = parse_bvh(text), parse_bvh(odd)
    assert funny.names == plain.names == ["Hips", "Chest", "Chest_End"]
    np.testing.assert_array_equal(funny.world_positions(), plain.world_positions())
    assert funny.frame_time == pytest.approx(0.04) and funny.fps == pytest.approx(25.0)


def test_end_sites_are_nodes_without_channels():
    bvh = parse_bvh(two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                                  "0 0 0 0 0 0"))
    assert list(bvh.is_end_site) == [False, False, True]
    assert bvh.channels[2] == () and list(bvh.parents) == [-1, 0, 1]
    assert bvh.children[1] == [2]


def test_read_from_file_and_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    tree = [("Hips", None, (0, 90, 0)), ("Spine", "Hips", (0, 10, 0)), ("Spine_End", "Spine", (0, 10, 0)),
            ("Leg", "Hips", (10, -5, 0)), ("Leg_End", "Leg", (0, -40, 0))]
    bvh = make_bvh(tree, motion=rng.uniform(-90, 90, (7, 12)), rotation_order="YXZ")
    path = tmp_path / "clip.bvh"
    path.write_text(format_bvh(bvh, precision=10))
    again = read_bvh(path)
    assert again.names == bvh.names and again.channels == bvh.channels
    np.testing.assert_allclose(again.world_positions(), bvh.world_positions(), atol=1e-6)
    np.testing.assert_allclose(again.world_positions(frames=[2, 5]), bvh.world_positions()[[2, 5]], atol=1e-6)


def test_fk_keeps_bone_lengths():
    rng = np.random.default_rng(2)
    tree = [("Hips", None, (0, 90, 0)), ("A", "Hips", (0, 10, 0)), ("B", "A", (3, 4, 0)), ("B_End", "B", (0, 0, 2))]
    bvh = make_bvh(tree, motion=rng.uniform(-180, 180, (50, 12)))
    p = bvh.world_positions()
    np.testing.assert_allclose(np.linalg.norm(p[:, 2] - p[:, 1], axis=-1), 5.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(p[:, 3] - p[:, 2], axis=-1), 2.0, atol=1e-12)


def _humanoid(up: str):
    """A minimal humanoid standing along +Y or +Z."""
    tree = [("Hips", None, (0, 0, 0)), ("LUp", "Hips", (1, -1, 0)), ("LLow", "LUp", (0, -4, 0)),
            ("LLow_End", "LLow", (0, -4, 0)), ("RUp", "Hips", (-1, -1, 0)), ("RLow", "RUp", (0, -4, 0)),
            ("RLow_End", "RLow", (0, -4, 0)), ("Spine", "Hips", (0, 3, 0)), ("Neck", "Spine", (0, 3, 0)),
            ("Neck_End", "Neck", (0, 1, 0)), ("LArm", "Spine", (1, 3, 0)), ("LArm_End", "LArm", (3, 0, 0)),
            ("RArm", "Spine", (-1, 3, 0)), ("RArm_End", "RArm", (-3, 0, 0))]
    if up == "z":
        tree = [(n, p, (o[0], -o[2], o[1])) for n, p, o in tree]
    return make_bvh(tree)


@pytest.mark.parametrize("up, expected", [("y", (1, 1.0)), ("z", (2, 1.0))])
def test_up_axis(up, expected):
    assert up_axis(_humanoid(up)) == expected


BAD = {
    "offset": ("  OFFSET 0 2 0\n", "  OFFSET 0 two 0\n", 8, "OFFSET"),
    "channel": ("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Wrotation", 9, "Wrotation"),
    "count": ("CHANNELS 3 Zrotation", "CHANNELS x Zrotation", 9, "integer"),
    "values": ("0 0 0 0 0 0 0 0 0\n", "0 0 0 0 0 0 0 0\n", 19, "8 values"),
    "nan": ("0 0 0 0 0 0 0 0 0\n", "0 0 0 0 0 nan 0 0 0\n", 19, "non-finite"),
    "word": ("0 0 0 0 0 0 0 0 0\n", "0 0 0 0 0 x 0 0 0\n", 19, "non-number"),
    "frames": ("Frames: 1", "Frames: 2", None, "only 1"),
    "frame_time": ("Frame Time: 0.04", "Frame Time: -1", 18, "positive"),
    "brace": ("    End Site\n    {\n", "    End Site\n    (\n", 11, "'{'"),
    "hierarchy": ("HIERARCHY", "HIERARCHX", 1, "HIERARCHY"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_malformed_files_name_file_and_line(case, tmp_path):
    good = two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "0 0 0 0 0 0")
    old, new, line, words = BAD[case]
    assert old in good
    path = tmp_path / "bad.bvh"
    path.write_text(good.replace(old, new, 1))
    with pytest.raises(InputError) as info:
        read_bvh(path)
    message = str(info.value)
    assert str(path) in message and words in message
    if line is not None:
        assert f"line {line}:" in message
    assert "\n" not in message


def test_extra_frame_line_is_reported(tmp_path):
    good = two_bone_text("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "0 0 0 0 0 0")
    path = tmp_path / "extra.bvh"
    path.write_text(good + "0 0 0 0 0 0 0 0 0\n")
    with pytest.raises(InputError, match="line 20: more frame lines"):
        read_bvh(path)


@pytest.mark.parametrize("text, words", [("", "empty"), ("HIERARCHY\nROOT a\n{\n", "MOTION"),
                                         ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n", "MOTION")])
def test_truncated_files(text, words, tmp_path):
    path = tmp_path / "t.bvh"
    path.write_text(text)
    with pytest.raises(InputError, match=words):
        read_bvh(path)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        read_bvh(tmp_path / "nope.bvh")


def test_shared_clips_read(shared_bvh_dir):
    for path in sorted(shared_bvh_dir.glob("*.bvh")):
        bvh = read_bvh(path)
        assert bvh.n_frames > 100 and bvh.motion.shape[1] == sum(len(c) for c in bvh.channels)
        p = bvh.world_positions(slice(0, 5))
        assert p.shape == (5, bvh.n_joints, 3) and np.all(np.isfinite(p))
        assert up_axis(bvh) == (1, 1.0), path.name   # the README: Y is up in all of them
