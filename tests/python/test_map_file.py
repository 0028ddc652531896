"""Map files (.slmap) from Python: ``_core.read_map_file_header`` on a file encoded here, byte by
byte, from the layout documented in cpp/slslam/map/map_io.h (a second writer that keeps the
documentation honest), and on foreign, damaged and newer files."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from slslam import _core


def fnv1a64(data: bytes) -> int:
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def string(s: str) -> bytes:
    raw = s.encode()
    return struct.pack("<I", len(raw)) + raw


def empty_map_section() -> bytes:
    """One keyframe (identity pose, no features, empty frame) and one point."""
    keyframe = struct.pack("<i", 0)
    keyframe += struct.pack("<9d", 1, 0, 0, 0, 1, 0, 0, 0, 1) + struct.pack("<3d", 0, 0, 0)
    keyframe += struct.pack("<iB", -1, 0)  # parent, bad
    keyframe += struct.pack("<5I", 0, 0, 0, 0, 0)  # covisibility, point/line ids, bow, index
    empty_mat = struct.pack("<3i", 0, 0, 0)
    frame = struct.pack("<id", 7, 12.5) + struct.pack("<3I", 0, 0, 0) + empty_mat
    frame += struct.pack("<3I", 0, 0, 0) + empty_mat + struct.pack("<2I", 0, 0)
    point = struct.pack("<i3d", 0, 1.0, 2.0, 3.0) + empty_mat + struct.pack("<I", 0)
    point += struct.pack("<3iB", 0, 0, 0, 0)
    return keyframe + frame + point


def map_file(version: int = 2, line_descriptor: str = "lbd") -> bytes:
    """Format 2; format 1 lacks the line descriptor name after the vocabulary name."""
    section = empty_map_section()
    payload = string("0.1.0") + struct.pack("<ii", 0, 32) + string("orb_vocabulary.slvoc")
    if version >= 2:
        payload += string(line_descriptor)
    payload += struct.pack("<4d2id", 458.0, 457.5, 367.2, 248.4, 752, 480, 0.11)
    payload += struct.pack("<3i", 1, 1, 0)  # next keyframe, point, line ids
    payload += struct.pack("<I", 1) + struct.pack("<4IQ", 1, 0, 1, 0, len(section)) + section
    return b"SLSLAMAP" + struct.pack("<IQQ", version, len(payload), fnv1a64(payload)) + payload


def test_header_of_a_file_written_from_the_documented_layout(tmp_path: Path) -> None:
    path = tmp_path / "atlas.slmap"
    path.write_bytes(map_file())
    header = _core.read_map_file_header(str(path))
    assert header["format_version"] == 2
    assert header["line_descriptor"] == "lbd"
    assert header["slslam_version"] == "0.1.0"
    assert header["descriptor_type"] == "binary"
    assert header["descriptor_cols"] == 32
    assert header["vocabulary"] == "orb_vocabulary.slvoc"
    assert header["camera"] == {
        "fx": 458.0,
        "fy": 457.5,
        "cx": 367.2,
        "cy": 248.4,
        "width": 752,
        "height": 480,
    }
    assert header["baseline_m"] == 0.11
    assert header["next_ids"] == {"keyframe": 1, "point": 1, "line": 0}
    assert header["maps"] == [{"keyframes": 1, "culled_keyframes": 0, "points": 1, "lines": 0}]


def test_format_one_files_still_load_as_opencv_line_descriptors(tmp_path: Path) -> None:
    path = tmp_path / "old.slmap"
    path.write_bytes(map_file(version=1))
    header = _core.read_map_file_header(str(path))
    assert header["format_version"] == 1
    assert header["line_descriptor"] == "opencv_lbd"
    assert header["vocabulary"] == "orb_vocabulary.slvoc"
    assert header["baseline_m"] == 0.11


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("cloud.ply", b"ply\nformat ascii 1.0\n", "not an slslam map file"),
        ("empty.slmap", b"", "not an slslam map file"),
        ("newer.slmap", map_file(version=4), "newer than this slslam reads"),
        ("unknown_lines.slmap", map_file(line_descriptor="sift"), "line descriptor 'sift'"),
        ("truncated.slmap", map_file()[:-5], "truncated"),
        ("flipped.slmap", map_file()[:-3] + b"\xff" + map_file()[-2:], "checksum mismatch"),
    ],
)
def test_bad_files_raise_value_error_naming_them(
    tmp_path: Path, name: str, content: bytes, message: str
) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(ValueError, match=message) as error:
        _core.read_map_file_header(str(path))
    assert str(path) in str(error.value)


def test_missing_file_raises_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="cannot open the map file"):
        _core.read_map_file_header(str(tmp_path / "missing.slmap"))
