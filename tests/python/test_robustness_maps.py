"""Damaged and crafted map files (.slmap) get a clear error, never a crash, a hang, another
exception or a silent acceptance; valid files (and valid variations of them) still load.

One small map is made per module (a simulated loop, tracked and saved), parsed here from the
layout documented at the top of cpp/slslam/map/map_io.h, and then spoilt in several classes of
cases, each written to its own file: random byte flips (the checksum catches them), truncations,
preamble fields, header fields and records changed with the checksum recomputed (id counters,
string lengths, camera, vocabulary identity, keyframe timestamps and poses, point and line
coordinates, ids and references). Every file is loaded in a worker process (so a crash or a hang
is seen as one, per case) by the real loader: ``_core.read_map_file_header`` where the defect is
in the header, and a ``slslam.Tracker`` built with ``load_map`` (the whole LoadMaps plus the
tracker's compatibility checks) for every case. The last test prints the counts per class.

Outcomes: ``error`` (a ValueError / InputError naming the file and the problem the case expects),
``accepted`` (a valid file loaded), ``tolerated`` (a random resealed change the checks cannot tell
from a valid map, loaded: allowed for the fuzz-resealed class only), and the failures ``silent``
(bad file accepted), ``refused`` (valid file refused), ``vague`` (an error without the file or
the expected problem), ``traceback`` (another exception), ``crash``, ``hang`` and
``inconsistent`` (the header read refuses what the full load accepts).
"""

from __future__ import annotations

import collections
import dataclasses
import json
import math
import os
import re
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

PREAMBLE = 28
INT32_MAX = 2**31 - 1
HEADROOM = 1 << 24  # map_io_detail::kIdHeadroom
HANG_S = 20.0  # one load taking longer than this counts as a hang
SEED = 20240611
#: failures, in the summary line
BAD_OUTCOMES = ("silent", "refused", "vague", "traceback", "crash", "hang", "inconsistent")

# ---------------------------------------------------------------------------------------------
# The file format (map_io.h), read here independently of the C++.


def fnv1a64(data: bytes, state: int = 0xCBF29CE484222325) -> int:
    """FNV-1a 64 of ``data``, continuing from ``state`` (the hash of what precedes it)."""
    h = state
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


class Reader:
    """Reads the documented layout and remembers where each field starts (file offsets)."""

    def __init__(self, data: bytes, offset: int) -> None:
        self.data = data
        self.o = offset

    def take(self, fmt: str) -> tuple:
        at = self.o
        values = struct.unpack_from("<" + fmt, self.data, at)
        self.o += struct.calcsize("<" + fmt)
        return values

    def one(self, fmt: str):
        return self.take(fmt)[0]

    def string(self) -> str:
        n = self.one("I")
        raw = self.data[self.o : self.o + n]
        self.o += n
        return raw.decode()

    def skip_list(self, entry_bytes: int) -> tuple[int, int]:
        """A u32 count and that many fixed-size entries: (offset of the first entry, count)."""
        n = self.one("I")
        at = self.o
        self.o += n * entry_bytes
        return at, n

    def mat(self) -> None:
        kind, rows, cols = self.take("3i")
        depth, channels = kind & 7, (kind >> 3) + 1
        element = {0: 1, 1: 1, 2: 2, 3: 2, 4: 4, 5: 4, 6: 8, 7: 2}[depth]
        self.o += rows * cols * channels * element


@dataclasses.dataclass
class Layout:
    """Offsets (in the file) of the fields the cases change."""

    version: int
    header: dict  # field -> value
    fields: dict  # field -> offset of its value (strings: of their u32 length)
    ids_at: int  # the three i32 id counters
    table_at: int  # u32 map count
    sections_at: int
    table: list[dict]
    keyframes: list[dict]
    points: list[dict]
    lines: list[dict]


def parse(data: bytes) -> Layout:
    """The whole file by the documented layout; fails unless it accounts for every byte."""
    assert data[:8] == b"SLSLAMAP"
    version, size, checksum = struct.unpack_from("<IQQ", data, 8)
    assert size == len(data) - PREAMBLE and checksum == fnv1a64(data[PREAMBLE:])
    r = Reader(data, PREAMBLE)
    header: dict = {}
    fields: dict = {}
    fields["slslam_version"] = r.o
    header["slslam_version"] = r.string()
    for name in ("descriptor_type", "descriptor_cols"):
        fields[name] = r.o
        header[name] = r.one("i")
    fields["vocabulary"] = r.o
    header["vocabulary"] = r.string()
    fields["line_descriptor"] = r.o
    header["line_descriptor"] = r.string()
    for name, fmt in (("fx", "d"), ("fy", "d"), ("cx", "d"), ("cy", "d")):
        fields[name] = r.o
        header[name] = r.one(fmt)
    for name in ("width", "height"):
        fields[name] = r.o
        header[name] = r.one("i")
    fields["baseline_m"] = r.o
    header["baseline_m"] = r.one("d")
    ids_at = r.o
    header["next_ids"] = r.take("3i")
    table_at = r.o
    table = []
    for _ in range(r.one("I")):
        at = r.o
        keyframes, retired, points, lines, nbytes = r.take("4IQ")
        table.append(
            dict(at=at, keyframes=keyframes, retired=retired, points=points, lines=lines)
            | dict(bytes=nbytes)
        )
    sections_at = r.o
    kfs, pts, lns = [], [], []
    for entry in table:
        begin = r.o
        for _ in range(entry["keyframes"]):
            kf = {"at": r.o, "id": r.one("i"), "R": r.o}
            r.o += 9 * 8
            kf["t"] = r.o
            r.o += 3 * 8
            kf["parent"] = r.o
            r.o += 4 + 1
            r.skip_list(8)  # covisibility
            kf["point_ids"], kf["n_point_ids"] = r.skip_list(4)
            r.skip_list(4)  # line ids
            kf["bow"], kf["n_bow"] = r.skip_list(12)
            for _ in range(r.one("I")):  # direct index
                r.o += 4
                r.skip_list(4)
            kf["index"] = r.o
            r.o += 4
            kf["t_ns"] = r.o
            kf["t_ns_value"] = r.one("q")
            kf["uv"], kf["n_keypoints"] = r.skip_list(8)
            r.skip_list(4)  # scores
            r.skip_list(4)  # octaves
            r.mat()
            r.skip_list(8)  # right columns
            kf["depth"], kf["n_depth"] = r.skip_list(8)
            r.skip_list(16)  # segments
            r.mat()
            kf["line_endpoints"], kf["n_line_endpoints"] = r.skip_list(48)
            r.skip_list(1)  # depth flags
            kfs.append(kf)
        for _ in range(entry["retired"]):
            r.o += 4 + 4 + 12 * 8
        for _ in range(entry["points"]):
            p = {"at": r.o, "id": r.one("i"), "position": r.o}
            p["xyz"] = r.take("3d")
            r.mat()
            p["observations"], p["n_observations"] = r.skip_list(8)
            r.o += 4 + 4
            p["first_keyframe"] = r.o
            r.o += 4 + 1
            pts.append(p)
        for _ in range(entry["lines"]):
            line = {"at": r.o, "id": r.one("i"), "n": r.o, "v": r.o + 24}
            line["start"], line["end"] = r.o + 48, r.o + 72
            r.o += 12 * 8
            r.mat()
            r.skip_list(8)
            r.o += 3 * 4 + 1
            lns.append(line)
        assert r.o - begin == entry["bytes"], "a section's size differs from its table entry"
    assert r.o == len(data), "the layout leaves bytes unread"
    return Layout(version, header, fields, ids_at, table_at, sections_at, table, kfs, pts, lns)


def encode_string(s: str) -> bytes:
    raw = s.encode()
    return struct.pack("<I", len(raw)) + raw


def encode_header(h: dict) -> bytes:
    """Header and id counters (the bytes from offset 28 to the map table)."""
    out = encode_string(h["slslam_version"]) + struct.pack(
        "<ii", h["descriptor_type"], h["descriptor_cols"]
    )
    out += encode_string(h["vocabulary"]) + encode_string(h["line_descriptor"])
    out += struct.pack(
        "<4d2id", h["fx"], h["fy"], h["cx"], h["cy"], h["width"], h["height"], h["baseline_m"]
    )
    return out + struct.pack("<3i", *h["next_ids"])


class Sealer:
    """Writes the preamble (size, checksum) of a changed payload; the hash of the unchanged
    prefix is taken from a table of the original's running hash, so a change near the end costs
    little."""

    def __init__(self, original: bytes) -> None:
        self.original = original
        self.states = [0] * (len(original) - PREAMBLE + 1)
        h = 0xCBF29CE484222325
        states = self.states
        states[0] = h
        for i, b in enumerate(original[PREAMBLE:], 1):
            h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
            states[i] = h

    def seal(self, data: bytes | bytearray, same_until: int = PREAMBLE) -> bytes:
        """``data`` with a correct preamble; its bytes before ``same_until`` (a file offset) are
        the original's."""
        payload = bytes(data[PREAMBLE:])
        start = max(0, min(same_until - PREAMBLE, len(payload), len(self.states) - 1))
        checksum = fnv1a64(payload[start:], self.states[start])
        version = struct.unpack_from("<I", data, 8)[0]  # (the data's own: 3, or 2 for f64 times)
        return bytes(data[:8]) + struct.pack("<IQQ", version, len(payload), checksum) + payload

    def patch(self, at: int, raw: bytes) -> bytes:
        """The original with ``raw`` written at ``at``, resealed."""
        data = bytearray(self.original)
        data[at : at + len(raw)] = raw
        return self.seal(data, same_until=at)


# ---------------------------------------------------------------------------------------------
# The cases.

HEADER, TRACKER = "header", "tracker"  # the loaders: read_map_file_header, Tracker(load_map=)
OK = None  # expectation: loads
ANY = "any"  # expectation: loads, or a clear error naming the file (a mutation it may not tell)


@dataclasses.dataclass
class Case:
    name: str
    cls: str  # class, for the summary line
    data: bytes
    #: loader -> regular expression the error must match (after the path), or OK
    expect: dict
    path: str = ""

    @property
    def valid(self) -> bool:
        return all(e is OK for e in self.expect.values())

    @property
    def bad(self) -> bool:
        return not self.valid and ANY not in self.expect.values()


def both(pattern: str | None) -> dict:
    return {HEADER: pattern, TRACKER: pattern}


def records(pattern: str) -> dict:
    """A defect in the records: the map does not load (the header read, which builds no map,
    may accept the file)."""
    return {HEADER: ANY, TRACKER: pattern}


def f64(x: float) -> bytes:
    return struct.pack("<d", x)


def i64(x: int) -> bytes:
    return struct.pack("<q", x)


def i32(x: int) -> bytes:
    return struct.pack("<i", x)


def u32(x: int) -> bytes:
    return struct.pack("<I", x)


def generate(original: bytes, layout: Layout, rng: np.random.Generator) -> list[Case]:
    s = Sealer(original)
    size = len(original)
    h = layout.header
    cases: list[Case] = []

    def add(cls: str, name: str, data: bytes, expect: dict) -> None:
        cases.append(Case(f"{cls}-{len(cases):03d}-{name}", cls, data, expect))

    def with_header(**changes) -> bytes:
        """The file with header fields changed (strings may change length), resealed."""
        new = dict(h) | changes
        body = encode_header(new) + original[layout.table_at :]
        return s.seal(original[:PREAMBLE] + body)

    # -- valid: the original, a copy, and valid variations (no false refusals) ---------------
    add("valid", "original", original, both(OK))
    add("valid", "copy", bytes(bytearray(original)), both(OK))
    add(
        "valid", "counters-at-headroom", with_header(next_ids=(INT32_MAX - HEADROOM,) * 3), both(OK)
    )
    name, _, checksum = h["vocabulary"].rpartition("@")
    add("valid", "vocabulary-renamed", with_header(vocabulary=f"moved.slvoc@{checksum}"), both(OK))
    add("valid", "vocabulary-legacy-name", with_header(vocabulary=name), both(OK))
    add("valid", "other-writer-version", with_header(slslam_version="9.9.9-dev+x"), both(OK))
    kf = layout.keyframes[-1]
    add("valid", "t_ns-9.1e18", s.patch(kf["t_ns"], i64(9_100_000_000_000_000_000)), both(OK))
    add("valid", "t_ns-negative", s.patch(kf["t_ns"], i64(-1)), both(OK))
    p = layout.points[len(layout.points) // 2]
    add("valid", "point-at-9.9e6", s.patch(p["position"], f64(-9.9e6)), both(OK))

    # -- preamble ------------------------------------------------------------------------------
    for magic in (b"slslamap", b"SLSLAMAQ", b"ply\nform", b"\0" * 8, b"SLSLAMA\0"):
        add("preamble", "magic", magic + original[8:], both("not an slslam map file"))
    for version, what in (
        (0, "format version 0"),
        (4, "newer"),
        (256, "newer"),
        (2**32 - 1, "newer"),
    ):
        add(
            "preamble",
            f"version-{version}",
            original[:8] + u32(version) + original[12:],
            both(what),
        )
    for payload, what in (
        (size - PREAMBLE + 1, r"announces .*\(truncated\)"),
        (2**64 - 1, r"\(truncated\)"),
        (size - PREAMBLE - 1, r"\(trailing data\)"),
        (0, r"\(trailing data\)"),
    ):
        data = original[:12] + struct.pack("<Q", payload) + original[20:]
        add("preamble", "size", data, both(what))
    stored = struct.unpack_from("<Q", original, 20)[0]
    for checksum_value in (stored ^ 1, 0, stored ^ (1 << 63)):
        data = original[:20] + struct.pack("<Q", checksum_value) + original[28:]
        add("preamble", "checksum", data, both("checksum mismatch"))
    for extra in (b"\0", bytes(4096)):
        add("preamble", "trailing", original + extra, both(r"\(trailing data\)"))

    # -- random single-byte flips: the checksum (or the preamble's own checks) must catch ------
    positions = list(rng.integers(0, PREAMBLE, 6)) + list(rng.integers(PREAMBLE, size, 30))
    for at in positions:
        at = int(at)
        mask = int(rng.integers(1, 256))
        data = bytearray(original)
        data[at] ^= mask
        if at < 8:
            what = "not an slslam map file"
        elif at < 12:
            version = struct.unpack_from("<I", data, 8)[0]
            what = "format version 0" if version == 0 else "newer" if version > 3 else "."
        elif at < 20:
            what = r"announces"
        else:
            what = "checksum mismatch"
        add("flip", f"byte-{at}-x{mask:02x}", bytes(data), both(what))

    # -- random byte changes resealed: a checked error or a map the checks cannot tell from a
    #    valid one (a changed mantissa, a count, a flag), never a crash, a hang or a traceback
    for at in rng.integers(PREAMBLE, size, 40):
        at = int(at)
        mask = int(rng.integers(1, 256))
        data = bytearray(original)
        data[at] ^= mask
        add("fuzz-resealed", f"byte-{at}-x{mask:02x}", s.seal(data, same_until=at), both(ANY))

    # -- truncations (the preamble still announces the whole file) -----------------------------
    lengths = [0, 3, 8, 20, 27, 28, 29] + sorted(int(n) for n in rng.integers(29, size, 15))
    for n in lengths:
        what = (
            "not an slslam map file"
            if n < 8
            else "shorter than the 28-byte preamble"
            if n < PREAMBLE
            else r"announces .*\(truncated\)"
        )
        add("truncated", f"to-{n}", original[:n], both(what))

    # -- truncations resealed (size and checksum agree): the structure must tell ---------------
    short = r"truncated|the file lacks them|but only \d+ bytes are left|bytes but \d+ follow"
    for n in [PREAMBLE, PREAMBLE + 2, layout.table_at + 2, layout.sections_at] + sorted(
        int(n) for n in rng.integers(PREAMBLE + 1, size, 14)
    ):
        expect = both(short) if n < layout.sections_at else both("the file lacks them")
        add("truncated-resealed", f"to-{n}", s.seal(original[:n], same_until=n), expect)

    # -- header fields, resealed -----------------------------------------------------------
    ids = layout.header["next_ids"]
    for k, counter in enumerate(("keyframe", "point", "line")):
        for value in (INT32_MAX, INT32_MAX - 1, INT32_MAX - HEADROOM + 1, -1, -(2**31)):
            new = list(ids)
            new[k] = value
            what = "negative id counters" if value < 0 else "leave fewer than 16777216 new ids"
            add(
                "header",
                f"next-{counter}-{value}",
                s.patch(layout.ids_at, struct.pack("<3i", *new)),
                both(what),
            )
    # counters below the file's own ids: the records tell
    for k, (counter, entries) in enumerate(
        (("keyframe", layout.keyframes), ("point", layout.points), ("line", layout.lines))
    ):
        new = list(ids)
        new[k] = max(e["id"] for e in entries)  # the largest id of the file: one beyond it
        add(
            "header",
            f"next-{counter}-too-low",
            s.patch(layout.ids_at, struct.pack("<3i", *new)),
            records(rf"{counter} id \d+ is outside \[0, {new[k]}\)"),
        )
    too_long = r"is \d+ bytes long, more than the \d+ allowed"
    for field, length in (
        ("slslam_version", 2**32 - 1),
        ("slslam_version", 257),
        ("vocabulary", 4097),
        ("vocabulary", 2**31),
        ("line_descriptor", 2**32 - 1),
        ("line_descriptor", 300),
    ):
        add(
            "header",
            f"{field}-length-{length}",
            s.patch(layout.fields[field], u32(length)),
            both(too_long),
        )
    add(
        "header",
        "slslam_version-length-past-end",
        s.patch(layout.fields["slslam_version"], u32(256)),
        both(r"\w"),
    )
    for field, value, what in (
        ("descriptor_type", 7, "descriptor type 7"),
        ("descriptor_type", 1, "descriptor type 1"),
        ("descriptor_type", -2, "descriptor type -2"),
        ("descriptor_cols", 0, "descriptor width 0"),
        ("descriptor_cols", -32, "descriptor width -32"),
        ("descriptor_cols", 1 << 20, "descriptor width 1048576"),
    ):
        add("header", f"{field}-{value}", s.patch(layout.fields[field], i32(value)), both(what))
    add(
        "header",
        "descriptor_cols-64",
        s.patch(layout.fields["descriptor_cols"], i32(64)),
        records(r"descriptor of type 0 with 32 columns, the file's header says type 0 with 64"),
    )
    add(
        "header",
        "line-descriptor-unknown",
        with_header(line_descriptor="sift"),
        both("line descriptor 'sift'"),
    )
    rig = "stereo rig: "
    for field, value, what in (
        ("fx", 0.0, "camera fx"),
        ("fx", math.nan, "camera fx"),
        ("fx", math.inf, "camera fx"),
        ("fx", 1e300, "camera fx"),
        ("fy", -458.0, "camera fy"),
        ("cx", math.nan, "principal point"),
        ("cy", -math.inf, "principal point"),
        ("baseline_m", math.nan, "baseline"),
        ("baseline_m", 1e300, "baseline"),
        ("baseline_m", 0.0, "baseline"),
        ("baseline_m", -0.11, "baseline"),
        ("baseline_m", math.inf, "baseline"),
    ):
        add(
            "header",
            f"{field}-{value}",
            s.patch(layout.fields[field], f64(value)),
            both(rig + ".*" + what),
        )
    for field, value in (("width", 0), ("height", 0), ("width", -752), ("height", 2**31 - 1)):
        add(
            "header",
            f"{field}-{value}",
            s.patch(layout.fields[field], i32(value)),
            both(rig + "camera image size"),
        )

    # -- map table, resealed ---------------------------------------------------------------
    entry = layout.table[0]
    # a count one off: the next record is misread as this one, whatever it then fails on
    misread = (
        r"truncated|unsupported matrix type|but only \d+ bytes are left|bytes left after"
        r"|negative size"
    )
    add(
        "table",
        "map-count-huge",
        s.patch(layout.table_at, u32(2**32 - 1)),
        both("map count is 4294967295 but only"),
    )
    add(
        "table",
        "map-count-2",
        s.patch(layout.table_at, u32(2)),
        both(r"the file lacks them|bytes but"),
    )
    add("table", "keyframes-huge", s.patch(entry["at"], u32(2**32 - 1)), both("cannot fit"))
    add("table", "points-huge", s.patch(entry["at"] + 8, u32(2**31)), both("cannot fit"))
    add(
        "table",
        "bytes-plus-1",
        s.patch(entry["at"] + 16, struct.pack("<Q", entry["bytes"] + 1)),
        both("the file lacks them"),
    )
    add(
        "table",
        "bytes-minus-1",
        s.patch(entry["at"] + 16, struct.pack("<Q", entry["bytes"] - 1)),
        both(r"the map sections take \d+ bytes but \d+ follow"),
    )
    add(
        "table",
        "points-minus-1",
        s.patch(entry["at"] + 8, u32(entry["points"] - 1)),
        records(misread),
    )
    add(
        "table",
        "points-plus-1",
        s.patch(entry["at"] + 8, u32(entry["points"] + 1)),
        records(misread),
    )
    add(
        "table",
        "lines-minus-1",
        s.patch(entry["at"] + 12, u32(entry["lines"] - 1)),
        records(r"bytes left after its entries"),
    )
    add(
        "table",
        "culled-plus-1",
        s.patch(entry["at"] + 4, u32(entry["retired"] + 1)),
        records(r"\w"),
    )

    # -- what the tracker checks beyond the file: another camera, vocabulary, line descriptor ---
    for field, value in (("fx", 500.0), ("cy", 200.0), ("baseline_m", 0.2)):
        add(
            "compat",
            f"camera-{field}",
            s.patch(layout.fields[field], f64(value)),
            records("the map was made with another camera"),
        )
    add(
        "compat",
        "camera-width",
        s.patch(layout.fields["width"], i32(640)),
        records("the map was made with another camera"),
    )
    other = "made with the vocabulary .* and this run loads another"
    for checksum_other in (
        "0" * 16,
        checksum[:-1] + ("0" if checksum[-1] != "0" else "1"),
        "f" * 16,
        f"{int(rng.integers(2**62)):016x}",
    ):
        add(
            "compat",
            "vocabulary",
            with_header(vocabulary=f"{name}@{checksum_other}"),
            records(other),
        )
    add(
        "compat",
        "vocabulary-short-checksum",
        with_header(vocabulary=f"{name}@{checksum[:8]}"),
        records(other),
    )
    other_lines = "lbd" if h["line_descriptor"] == "opencv_lbd" else "opencv_lbd"
    add(
        "compat",
        "line-descriptor",
        with_header(line_descriptor=other_lines),
        records(r"the map's lines carry"),
    )
    empty = s.seal(original[: layout.table_at] + u32(0), same_until=layout.table_at)
    add("compat", "no-map", empty, records("the file holds no map"))

    # -- keyframe records, resealed ------------------------------------------------------------
    kfs = layout.keyframes
    # Format version 2: the same file with f64 frame times [s]; it loads, and a time that is not
    # finite or beyond int64 nanoseconds is refused.
    v2 = bytearray(original)
    v2[8:12] = u32(2)
    for kf in kfs:
        v2[kf["t_ns"] : kf["t_ns"] + 8] = f64(kf["t_ns_value"] / 1e9)
    s2 = Sealer(s.seal(v2))
    add("compat", "version-2-seconds", s2.original, both(OK))
    for value in (1e300, -1e300, math.inf, -math.inf, math.nan, 2e10, -2e10, 9.3e9):
        for kf in rng.choice(len(kfs), 2, replace=False):
            kf = kfs[int(kf)]
            add(
                "keyframe-timestamp",
                f"kf{kf['id']}-{value}",
                s2.patch(kf["t_ns"], f64(value)),
                records(rf"keyframe {kf['id']}: frame timestamp .* is not finite or beyond"),
            )
    for value in (1e300, math.inf, -math.inf, math.nan, 2e10, -1.0000001e7):
        for _ in range(2):
            kf = kfs[int(rng.integers(len(kfs)))]
            c = int(rng.integers(3))
            add(
                "keyframe-pose",
                f"kf{kf['id']}-t{c}-{value}",
                s.patch(kf["t"] + 8 * c, f64(value)),
                records(rf"keyframe {kf['id']}: pose is not finite, beyond"),
            )
    kf = kfs[int(rng.integers(len(kfs)))]
    rotation = struct.unpack_from("<9d", original, kf["R"])
    for label, values in (
        ("nan", (math.nan,) + rotation[1:]),
        ("scaled", tuple(2 * v for v in rotation)),
        ("reflected", tuple(-v for v in rotation)),
        ("1e300", (1e300,) + rotation[1:]),
    ):
        add(
            "keyframe-pose",
            f"kf{kf['id']}-R-{label}",
            s.patch(kf["R"], struct.pack("<9d", *values)),
            records(
                rf"keyframe {kf['id']}: pose is not finite, beyond .* rotation is not orthonormal"
            ),
        )
    with_lines = [kf for kf in kfs if kf["n_line_endpoints"] > 0]
    for value in (math.nan, math.inf, 1e300, -2e7):
        kf = with_lines[int(rng.integers(len(with_lines)))]
        at = (
            kf["line_endpoints"]
            + 48 * int(rng.integers(kf["n_line_endpoints"]))
            + 8 * int(rng.integers(6))
        )
        add(
            "keyframe-frame",
            f"kf{kf['id']}-line-endpoint-{value}",
            s.patch(at, f64(value)),
            records(rf"keyframe {kf['id']}: a stereo line endpoint is not finite"),
        )
    with_points = [kf for kf in kfs if kf["n_keypoints"] > 0]
    kf = with_points[int(rng.integers(len(with_points)))]
    k = int(rng.integers(kf["n_keypoints"]))
    add(
        "keyframe-frame",
        f"kf{kf['id']}-depth-nan",
        s.patch(kf["depth"] + 8 * k, f64(math.nan)),
        records(rf"keyframe {kf['id']}: a right column or depth is not finite"),
    )
    for value in (1e300, -5.0, 0.0, 2e7):
        add(
            "keyframe-frame",
            f"kf{kf['id']}-depth-{value}",
            s.patch(kf["depth"] + 8 * k, f64(value)),
            records(rf"keyframe {kf['id']}: depth .* m is neither -1 \(none\) nor in"),
        )
    for value in (1e30, -2e6):
        add(
            "keyframe-frame",
            f"kf{kf['id']}-uv-{value}",
            s.patch(kf["uv"] + 8 * k, struct.pack("<f", value)),
            records(rf"keyframe {kf['id']}: a keypoint position is not finite or beyond"),
        )
    add(
        "keyframe-frame",
        f"kf{kf['id']}-uv-inf",
        s.patch(kf["uv"] + 8 * k, struct.pack("<f", math.inf)),
        records(rf"keyframe {kf['id']}: a keypoint position is not finite"),
    )
    add(
        "keyframe-frame",
        f"kf{kf['id']}-index--1",
        s.patch(kf["index"], i32(-1)),
        records(rf"keyframe {kf['id']}: frame index -1 is negative"),
    )
    add(
        "keyframe-frame",
        f"kf{kf['id']}-point-id-unknown",
        s.patch(kf["point_ids"] + 4 * k, i32(ids[1] + 5)),
        records(rf"keyframe {kf['id']}: unknown point id"),
    )
    if kf["n_bow"]:
        add(
            "keyframe-frame",
            f"kf{kf['id']}-bow-weight-nan",
            s.patch(kf["bow"] + 4, f64(math.nan)),
            records(rf"keyframe {kf['id']}: word \d+ has weight nan"),
        )
        for value in (1e300, 2.0, -0.5):
            add(
                "keyframe-frame",
                f"kf{kf['id']}-bow-weight-{value}",
                s.patch(kf["bow"] + 4, f64(value)),
                records(rf"keyframe {kf['id']}: word \d+ has weight .* L1-normalised"),
            )
    add(
        "keyframe-ids",
        "kf-id-repeated",
        s.patch(kfs[1]["at"], i32(kfs[0]["id"])),
        records(r"keyframe id \d+ follows \d+ \(ids must ascend\)"),
    )
    add(
        "keyframe-ids",
        "kf-id-negative",
        s.patch(kfs[0]["at"], i32(-7)),
        records(r"keyframe id -7 is outside"),
    )
    add(
        "keyframe-ids",
        "kf-parent-unknown",
        s.patch(kfs[-1]["parent"], i32(ids[0] + 3)),
        records(rf"keyframe {kfs[-1]['id']}: parent \d+ is not another keyframe"),
    )
    add(
        "keyframe-ids",
        "kf-parent-self",
        s.patch(kfs[-1]["parent"], i32(kfs[-1]["id"])),
        records(rf"keyframe {kfs[-1]['id']}: parent \d+ is not another keyframe"),
    )

    # -- point records, resealed ------------------------------------------------------------
    pts = layout.points
    for value in (1e300, -1e300, math.inf, -math.inf, math.nan, 1.0000001e7, -2e10):
        for p in rng.choice(len(pts), 3, replace=False):
            p = pts[int(p)]
            c = int(rng.integers(3))
            add(
                "point-position",
                f"p{p['id']}-{c}-{value}",
                s.patch(p["position"] + 8 * c, f64(value)),
                records(rf"point {p['id']}: position is not finite or beyond"),
            )
    p = pts[-1]
    add(
        "point-ids",
        "point-id-at-counter",
        s.patch(p["at"], i32(ids[1])),
        records(rf"point id {ids[1]} is outside \[0, {ids[1]}\)"),
    )
    add(
        "point-ids",
        "point-id-repeated",
        s.patch(pts[1]["at"], i32(pts[0]["id"])),
        records(r"point id \d+ follows \d+ \(ids must ascend\)"),
    )
    add(
        "point-ids",
        "point-first-keyframe",
        s.patch(p["first_keyframe"], i32(ids[0])),
        records(rf"point {p['id']}: first keyframe {ids[0]} is outside"),
    )
    observed = [p for p in pts if p["n_observations"] > 0]
    p = observed[int(rng.integers(len(observed)))]
    add(
        "point-ids",
        "point-observation-index",
        s.patch(p["observations"] + 4, i32(10**6)),
        records(rf"point {p['id']}: observed as feature 1000000 of keyframe"),
    )
    add(
        "point-ids",
        "point-observation-keyframe",
        # the last observation, so that the keyframe ids still ascend
        s.patch(p["observations"] + 8 * (p["n_observations"] - 1), i32(ids[0] + 9)),
        records(rf"point {p['id']}: observed in \d+, not a keyframe of the map"),
    )

    # -- map line records, resealed ---------------------------------------------------------
    lns = layout.lines
    for value in (1e300, -1e300, math.nan, math.inf, 2e7, -1.0000001e7):
        line = lns[int(rng.integers(len(lns)))]
        end = ("start", "end")[int(rng.integers(2))]
        c = int(rng.integers(3))
        add(
            "line",
            f"l{line['id']}-{end}{c}-{value}",
            s.patch(line[end] + 8 * c, f64(value)),
            records(rf"line {line['id']}: not finite, endpoints beyond"),
        )
    line = lns[int(rng.integers(len(lns)))]
    add(
        "line",
        f"l{line['id']}-no-direction",
        s.patch(line["v"], struct.pack("<3d", 0, 0, 0)),
        records(rf"line {line['id']}: not finite, endpoints beyond .* no direction"),
    )
    add(
        "line",
        f"l{line['id']}-moment-nan",
        s.patch(line["n"], f64(math.nan)),
        records(rf"line {line['id']}: not finite"),
    )
    return cases


# ---------------------------------------------------------------------------------------------
# The worker: loads each case in a process of its own, so that a crash or a hang is one case's.


def worker(sequence: str, cases_file: str, results_file: str, start: int) -> None:
    """Loads the cases from ``start`` on, one result line (JSON) each, flushed as it is known."""
    from slslam import Tracker, _core, default_config
    from slslam.tracking.run import open_dataset

    camera = open_dataset(sequence).camera
    config = default_config()
    jobs = [json.loads(line) for line in Path(cases_file).read_text().splitlines()]
    loaders = {
        HEADER: lambda path: _core.read_map_file_header(path),
        TRACKER: lambda path: Tracker(camera, config, load_map=path).close(),
    }
    with open(results_file, "a", encoding="utf-8") as out:
        for index in range(start, len(jobs)):
            job = jobs[index]
            result = {"index": index, "outcomes": {}}
            for loader in job["loaders"]:
                t0 = time.perf_counter()
                try:
                    loaders[loader](job["path"])
                    outcome = {"ok": True}
                except Exception as exc:  # classified by the parent
                    outcome = {"type": type(exc).__name__, "message": str(exc)}
                    outcome["value_error"] = isinstance(exc, ValueError)
                outcome["s"] = time.perf_counter() - t0
                result["outcomes"][loader] = outcome
            out.write(json.dumps(result) + "\n")
            out.flush()


def run_worker(sequence: Path, cases: list[Case], folder: Path) -> dict[int, dict]:
    """Results per case index; a case during which the worker died or hung gets
    ``{"crash": ...}`` or ``{"hang": ...}`` and the worker goes on from the next case."""
    import slslam

    cases_file = folder / "cases.jsonl"
    results_file = folder / "results.jsonl"
    cases_file.write_text(
        "".join(json.dumps({"path": c.path, "loaders": list(c.expect)}) + "\n" for c in cases)
    )
    results_file.write_text("")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(slslam.__file__).resolve().parents[1]), env.get("PYTHONPATH", "")]
    )
    results: dict[int, dict] = {}
    start = 0
    while start < len(cases):
        proc = subprocess.Popen(
            [sys.executable, __file__, "--worker", str(sequence), str(cases_file)]
            + [str(results_file), str(start)],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        last_progress = time.monotonic()
        seen = len(results)
        while True:
            code = proc.poll()
            for line in results_file.read_text().splitlines():
                result = json.loads(line)
                results.setdefault(result["index"], result)
            if len(results) > seen:
                seen, last_progress = len(results), time.monotonic()
            if code is not None:
                break
            # the first case also waits for the worker's imports
            if time.monotonic() - last_progress > HANG_S + (10 if seen == start else 0):
                proc.kill()
                proc.wait()
                break
            time.sleep(0.05)
        stderr = proc.stderr.read().decode(errors="replace")[-2000:]
        proc.stderr.close()
        pending = [i for i in range(start, len(cases)) if i not in results]
        if not pending:
            break
        if code == 0:  # finished without answering: a bug of the harness, not of the loader
            raise AssertionError(f"the worker skipped cases {pending[:5]}: {stderr}")
        kind = "crash" if code is not None else "hang"
        results[pending[0]] = {kind: f"exit {code}: {stderr}"}
        start = pending[0] + 1
    return results


def classify(case: Case, result: dict) -> tuple[str, str]:
    """The outcome class of a case and, for a failure, what went wrong."""
    tolerated = False
    if "crash" in result or "hang" in result:
        kind = "crash" if "crash" in result else "hang"
        return kind, result[kind]
    for loader, pattern in case.expect.items():
        outcome = result["outcomes"][loader]
        if outcome["s"] > HANG_S:
            return "hang", f"{loader} took {outcome['s']:.1f} s"
        if outcome.get("ok"):
            tolerated |= pattern == ANY and loader == TRACKER
            if pattern not in (OK, ANY):
                return "silent", f"{loader} accepted it (expected an error matching {pattern!r})"
            continue
        message = outcome["message"]
        if not outcome["value_error"]:
            return "traceback", f"{loader}: {outcome['type']}: {message}"
        if pattern is OK:
            return "refused", f"{loader}: {message}"
        # the path, then the problem after it (the tracker prefixes the path once more)
        problem = message.split(case.path + ": ")[-1]
        if pattern == ANY:
            pattern = r"\w"
        if case.path not in message or not re.search(pattern, problem) or len(problem) < 12:
            return "vague", f"{loader}: {outcome['type']}: {message!r} (expected {pattern!r})"
    header, tracker = (result["outcomes"].get(k, {}) for k in (HEADER, TRACKER))
    if tracker.get("ok") and header and not header.get("ok"):
        return "inconsistent", f"the header read refused it, the tracker loaded it: {header}"
    return ("accepted" if case.valid else "tolerated" if tolerated else "error"), ""


# ---------------------------------------------------------------------------------------------
# The tests.


@pytest.fixture(scope="module")
def saved_map(tmp_path_factory):
    """A small map: a simulated loop of 30 frames, tracked and saved."""
    from slslam import run_sequence
    from slslam.sim import SimOptions, Simulator

    root = tmp_path_factory.mktemp("robustness_maps")
    sequence = root / "sequence"
    Simulator(SimOptions(preset="loop", frames=30, lidar=False)).write(sequence, progress=False)
    map_path = root / "atlas.slmap"
    run_sequence(sequence, root / "run", progress=False, save_map=map_path)
    return sequence, map_path


@pytest.fixture(scope="module")
def outcomes(saved_map, tmp_path_factory):
    """Every case generated, loaded and classified: (case, class, detail) per case."""
    sequence, map_path = saved_map
    original = map_path.read_bytes()
    layout = parse(original)
    cases = generate(original, layout, np.random.default_rng(SEED))
    folder = tmp_path_factory.mktemp("robustness_map_cases")
    for case in cases:
        path = folder / f"{case.name}.slmap"
        path.write_bytes(case.data)
        case.path = str(path)
        case.data = b""
    results = run_worker(sequence, cases, folder)
    classified = [(case, *classify(case, results[i])) for i, case in enumerate(cases)]
    yield classified
    # keep the files of the failing cases only (each is ~0.5 MB)
    for case, outcome, _ in classified:
        if outcome in ("error", "accepted", "tolerated"):
            Path(case.path).unlink(missing_ok=True)


def test_the_layout_parsed_here_matches_the_saved_map(saved_map):
    """The documented layout accounts for every byte of a real file (the cases rely on it)."""
    from slslam import _core

    _, map_path = saved_map
    layout = parse(map_path.read_bytes())
    header = _core.read_map_file_header(str(map_path))
    assert layout.header["vocabulary"] == header["vocabulary"]
    assert tuple(header["next_ids"].values()) == layout.header["next_ids"]
    assert len(layout.keyframes) == header["maps"][0]["keyframes"] >= 2
    assert len(layout.points) == header["maps"][0]["points"] >= 10
    assert len(layout.lines) == header["maps"][0]["lines"] >= 2
    assert "@" in layout.header["vocabulary"]  # a vocabulary identity with its checksum
    assert any(kf["n_line_endpoints"] for kf in layout.keyframes)


def test_a_saved_map_loads_into_a_run(saved_map, tmp_path):
    from slslam import run_sequence

    sequence, map_path = saved_map
    summary = run_sequence(
        sequence, tmp_path / "run", progress=False, max_frames=1, load_map=map_path
    )
    assert summary is not None


def test_every_bad_map_file_gets_a_clear_error_and_valid_ones_load(outcomes):
    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    failures = []
    for case, outcome, detail in outcomes:
        counts[case.cls][outcome] += 1
        counts[case.cls]["cases"] += 1
        if outcome not in ("error", "accepted", "tolerated"):
            failures.append(f"{case.name} [{outcome}] {detail}  ({case.path})")
    total = collections.Counter()
    for c in counts.values():
        total.update(c)
    parts = []
    for cls, c in sorted(counts.items()) + [("all", total)]:
        other = sum(c[k] for k in BAD_OUTCOMES)
        tolerated = f", {c['tolerated']} tolerated" if c["tolerated"] else ""
        parts.append(
            f"{cls}: {c['cases']} cases, {c['error']} errors, {c['accepted']} accepted"
            f"{tolerated}, {other} other"
        )
    print("\nmap file robustness: " + "; ".join(parts))
    bad_cases = sum(1 for case, _, _ in outcomes if case.bad)
    assert bad_cases >= 100
    assert total["accepted"] >= 5
    assert not failures, "\n".join(failures)


if __name__ == "__main__" and len(sys.argv) == 6 and sys.argv[1] == "--worker":
    worker(sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]))
