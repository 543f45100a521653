"""``python -m core evaluate`` end to end on a short built-in clip, and the PNG writer."""

from __future__ import annotations

import json
import struct
import zlib

import numpy as np

from core.cli import main
from core.estimate import METHODS
from core.io.png_plot import encode_png, scatter_image


def test_evaluate_prints_tables_writes_json_and_plot(tmp_path, capsys, monkeypatch):
    # A method that cannot even be loaded must be reported without stopping the others.
    monkeypatch.setitem(METHODS, "broken", (".peng_li.params", "no_such_function"))
    out = tmp_path / "eval.json"
    plots = tmp_path / "plots"
    code = main(["evaluate", "--builtin", "--method", "broken,paper", "--max-frames", "240",
                 "--json", str(out), "--plot-dir", str(plots)])
    assert code == 0
    text = capsys.readouterr().out
    assert "FAILED" in text and "mean |error|" in text and "summary" in text
    # the paper method takes its focal length from the hint or the default: the table must not pass
    # that off as a calibration (here the default happens to equal the synthetic camera's 50 mm)
    assert "focal f0 error +0.00 % (not determined: hint or default)" in text and "\n* f0 %" in text
    doc = json.loads(out.read_text())
    rows = {r["method"]: r for r in doc["results"]}
    assert "error" in rows["broken"]
    score = rows["paper"]["score"]
    assert 0 <= score["proportions"]["mean_abs"] <= 1.27
    assert 0 <= score["spells"]["frame_accuracy"] <= 1
    png = (plots / "builtin_walk_paper_scale.png").read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n")


def test_png_encoding_round_trips():
    img = scatter_image([(np.linspace(1, 0.5, 50), (255, 0, 0)), (np.linspace(1, 0.6, 50), (0, 0, 255))],
                        width=120, height=80)
    data = encode_png(img)
    w, h = struct.unpack(">II", data[16:24])
    assert (w, h) == (120, 80)
    # Decode the single IDAT chunk and compare with the image.
    pos = 8
    idat = b""
    while pos < len(data):
        length = struct.unpack(">I", data[pos:pos + 4])[0]
        tag = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        assert zlib.crc32(tag + body) & 0xFFFFFFFF == struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0]
        if tag == b"IDAT":
            idat += body
        pos += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, 1 + w * 3)
    assert np.all(raw[:, 0] == 0)
    assert np.array_equal(raw[:, 1:].reshape(h, w, 3), img)
    assert (img == [255, 0, 0]).all(axis=-1).any() and (img == [0, 0, 255]).all(axis=-1).any()


def test_evaluate_with_missing_joints_scores_every_frame(tmp_path, capsys):
    out = tmp_path / "eval.json"
    code = main(["evaluate", "--builtin", "--method", "joint", "--max-frames", "90", "--dropout", "0.2",
                 "--occlusion-s", "1", "--json", str(out)])
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["settings"]["dropout"] == 0.2 and doc["settings"]["occlusion_s"] == 1.0
    (row,) = doc["results"]
    assert "error" not in row and row["frames"] == 90
    assert row["score"]["proportions"]["mean_abs"] < 2.0
    assert row["score"]["mpjpe_frame_mm"] < 300  # a full 3D result despite the holes


def test_evaluate_continuous_camera_has_no_still_spell_between_motions(tmp_path, capsys):
    out = tmp_path / "eval.json"
    code = main(["evaluate", "--builtin", "--method", "paper", "--max-frames", "240", "--continuous",
                 "--kinds", "rotate_zoom,roll", "--json", str(out)])
    assert code == 0
    (line,) = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip().startswith("spells true")]
    kinds = line.split()[-1].split("/")
    assert kinds[0] == "still" and "still" not in kinds[1:] and {"rotate_zoom", "roll"} <= set(kinds)
    doc = json.loads(out.read_text())
    assert doc["settings"]["continuous"] is True and doc["settings"]["kinds"] == ["rotate_zoom", "roll"]


def test_evaluate_over_several_seeds_pools_the_runs(tmp_path, capsys):
    out = tmp_path / "eval.json"
    code = main(["evaluate", "--builtin", "--method", "paper", "--max-frames", "120", "--seeds", "0,1,1",
                 "--json", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["settings"]["seeds"] == [0, 1]          # a repeated seed runs once
    rows = doc["results"]
    assert [(r["clip"], r["seed"]) for r in rows] == [("builtin:walk s0", 0), ("builtin:walk s1", 1)]
    # two draws film the walk differently
    assert rows[0]["score"]["proportions"]["mean_abs"] != rows[1]["score"]["proportions"]["mean_abs"]
    pooled = [line for line in text.splitlines() if line.startswith("paper ") and "runs" in line]
    assert "pooled over 2 seeds" in text and len(pooled) == 1
    mean = np.mean([r["score"]["proportions"]["mean_abs"] for r in rows])
    assert f"{mean:.3f} / " in pooled[0]
    assert "ALL (2 runs)" in text


def test_evaluate_refuses_a_malformed_seed_list(capsys):
    assert main(["evaluate", "--builtin", "--method", "paper", "--max-frames", "60", "--seeds", "0,x"]) == 2
    assert "--seeds" in capsys.readouterr().err


def test_pooled_skips_scores_that_do_not_apply():
    # metrics give NaN (a clip with no clear stance) or None (no zoom): such a run must not poison the pool
    from core.evaluation.evaluate import pooled

    def sc(mean, stance, zoom):
        return {"proportions": {"mean_abs": mean, "max_abs": 2 * mean}, "rotation_error_deg": 1.0,
                "zoom_focal_error_pct": zoom, "stance_accuracy": stance}

    a = pooled([sc(0.1, 0.9, 2.0), sc(0.3, float("nan"), None), sc(0.2, 0.8, float("nan"))])
    assert a["runs"] == 3 and abs(a["mean_pp"] - 0.2) < 1e-12 and a["max_pp"] == 0.6
    assert abs(a["stance_pct"] - 85.0) < 1e-9 and a["zoom_focal_pct"] == 2.0
    assert "mpjpe_frame_mm" not in a
