"""The shared JSON rules: one-line errors naming the file, whole-or-nothing writes."""

from __future__ import annotations

import json

import pytest

from core.errors import InputError
from core.io.file_io import check_header, read_json_file, write_json_atomic
from core.result import read_estimate_json


@pytest.mark.parametrize(("content", "message"), [
    (b"", "file is empty"),
    (b"  \n", "file is empty"),
    (b"\xff\xfe", "not a UTF-8 text file"),
    (b'{"a": 1,\n', "invalid JSON at line 2, column 1"),
    (b"[" * 100000, "nested too deeply"),
])
def test_read_errors_name_the_file_and_the_problem(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    with pytest.raises(InputError) as info:
        read_json_file(path)
    text = str(info.value)
    assert text.startswith(str(path)) and message in text and "\n" not in text


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="cannot read file"):
        read_json_file(tmp_path / "nope.json")


def test_nan_tokens_become_numbers_for_the_validator_to_locate(tmp_path):
    path = tmp_path / "nan.json"
    path.write_text('{"x": NaN}')
    value = read_json_file(path)["x"]
    assert isinstance(value, float) and value != value  # NaN reaches the format's validator


def test_atomic_write_replaces_whole_and_failure_leaves_nothing(tmp_path):
    target = tmp_path / "out.json"
    write_json_atomic({"a": [1, 2]}, target)
    assert json.loads(target.read_text()) == {"a": [1, 2]}
    assert not (tmp_path / "out.json.tmp").exists()
    # a document json cannot encode fails after the temp file was opened: no temp, old file intact
    with pytest.raises(TypeError):
        write_json_atomic({"a": object()}, target)
    assert json.loads(target.read_text()) == {"a": [1, 2]}
    missing_dir = tmp_path / "no" / "such" / "dir" / "out.json"
    with pytest.raises(InputError, match="cannot write result file"):
        write_json_atomic({}, missing_dir, what="result file")


def test_header_check_and_estimate_reader(tmp_path):
    with pytest.raises(InputError, match="not a 'skeleton-estimate' file"):
        check_header({"format": "x"}, "skeleton-estimate", 1, "f.json: ")
    with pytest.raises(InputError, match="unsupported skeleton-estimate version 2"):
        check_header({"format": "skeleton-estimate", "version": 2}, "skeleton-estimate", 1, "")
    path = tmp_path / "r.json"
    path.write_text('{"format": "skeleton-tracks", "version": 1}')
    with pytest.raises(InputError, match=r"r\.json: not a 'skeleton-estimate' file"):
        read_estimate_json(path)


def test_text_and_bytes_are_written_as_given_and_text_reads_back(tmp_path):
    from core.io.file_io import read_text, write_atomic

    write_atomic(tmp_path / "a.csv", "x,y\r\n1,2\n")
    assert (tmp_path / "a.csv").read_bytes() == b"x,y\r\n1,2\n"    # no newline translation
    write_atomic(tmp_path / "b.png", b"\x89PNG\x00")
    assert (tmp_path / "b.png").read_bytes() == b"\x89PNG\x00"
    (tmp_path / "bom.json").write_bytes(b"\xef\xbb\xbf{}")
    assert read_text(tmp_path / "bom.json") == "{}"
    (tmp_path / "nul.csv").write_bytes(b"a\x00b")
    with pytest.raises(InputError, match="NUL bytes"):
        read_text(tmp_path / "nul.csv")
    with pytest.raises(InputError, match="cannot write plot"):
        write_atomic(tmp_path / "missing" / "c.png", b"", what="plot")
