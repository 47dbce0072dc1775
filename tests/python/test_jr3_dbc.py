"""The JR3 CAN layout three ways: docs/INTERFACE.md (written out here), proto/jr3.dbc
(read by cantools) and the C encoder of drivers/ (through the helper
program tests/tools/jr3_encode_log, whose path ctest passes in
LOADID_JR3_ENCODE_LOG; it writes candump lines with drivers/' formatter).

* the DBC says what docs/INTERFACE.md says: ids 0x1A0..0x1A4, DLC 8, three
  little-endian int16 at bits 0/16/32 with the default full scale / 16384,
  sequence in byte 6, status bits in byte 7, base+4 multiplexed by group with
  uint16 full scales in 0.1 N, 0.01 N m, 0.01 m/s^2, 0.1 rad/s^2;
* cantools decodes the C encoder's frames to the values put in, within half
  a count, with the saturation and fault bits where they belong;
* the candump lines are read back by an independent parser (a regular
  expression here, cantools' log reader, and can-utils' log2asc when
  installed).
"""

from __future__ import annotations

import io
import os
import pathlib
import random
import re
import shutil
import subprocess

import cantools
import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
DBC_PATH = REPO_ROOT / "proto" / "jr3.dbc"
BASE = 0x1A0
GROUPS = ["Force", "Moment", "Linear", "Angular"]
# docs/INTERFACE.md: default full scales (N, N m, m/s^2, rad/s^2) and base+4 units.
FULL_SCALE = {"Force": 200.0, "Moment": 12.0, "Linear": 98.1, "Angular": 1000.0}
FS_UNIT = {"Force": 0.1, "Moment": 0.01, "Linear": 0.01, "Angular": 0.1}
UNIT_TEXT = {"Force": "N", "Moment": "N.m", "Linear": "m/s^2", "Angular": "rad/s^2"}

# candump -l: "(%010lu.%06lu) <ifname> <3 or 8 hex>#<hex pairs>"
CANDUMP_LINE = re.compile(
    r"^\((?P<sec>\d{10,})\.(?P<usec>\d{6})\) (?P<ifname>\S+) "
    r"(?P<id>[0-9A-F]{3}|[0-9A-F]{8})#(?P<data>(?:[0-9A-F]{2}){0,8})$")


@pytest.fixture(scope="module")
def db():
    return cantools.database.load_file(str(DBC_PATH), strict=True)


def encoder() -> str:
    path = os.environ.get("LOADID_JR3_ENCODE_LOG")
    if not path or not os.path.isfile(path):
        pytest.fail("LOADID_JR3_ENCODE_LOG must name the jr3_encode_log program "
                    "(ctest sets it; build target jr3_encode_log)")
    return path


def run_encoder(commands: list[str]) -> list[str]:
    res = subprocess.run([encoder()], input="\n".join(commands) + "\n", capture_output=True,
                         text=True, check=False, timeout=60)
    assert res.returncode == 0, res.stderr
    return res.stdout.splitlines()


def parse_line(line: str):
    """(t_us, ifname, id, extended, data) by the regular expression alone."""
    m = CANDUMP_LINE.match(line)
    assert m, f"not a candump -l line: {line!r}"
    t_us = int(m["sec"]) * 1_000_000 + int(m["usec"])
    return t_us, m["ifname"], int(m["id"], 16), len(m["id"]) == 8, bytes.fromhex(m["data"])


def test_dbc_matches_design(db):
    assert [m.frame_id for m in db.messages] == [BASE + i for i in range(5)]
    for msg in db.messages:
        assert msg.length == 8
        assert not msg.is_extended_frame
        assert msg.senders == ["JR3"]
    for i, g in enumerate(GROUPS):
        msg = db.get_message_by_frame_id(BASE + i)
        assert not msg.is_multiplexed()
        for k, axis in enumerate("XYZ"):
            s = msg.get_signal_by_name(f"{g}_{axis}")
            assert (s.start, s.length, s.byte_order, s.is_signed) == (16 * k, 16, "little_endian",
                                                                     True)
            # The factor of the DEFAULT full scale, to the last bit of a double.
            assert s.scale == FULL_SCALE[g] / 16384
            assert s.offset == 0
            assert s.unit == UNIT_TEXT[g]
            assert s.minimum == pytest.approx(-32768 * FULL_SCALE[g] / 16384, rel=1e-15)
            assert s.maximum == pytest.approx(32767 * FULL_SCALE[g] / 16384, rel=1e-15)
        seq = msg.get_signal_by_name("Sequence")
        assert (seq.start, seq.length, seq.is_signed, seq.scale) == (48, 8, False, 1)
        sat = msg.get_signal_by_name("Saturated")
        flt = msg.get_signal_by_name("Fault")
        res = msg.get_signal_by_name("StatusReserved")
        assert (sat.start, sat.length) == (56, 1)
        assert (flt.start, flt.length) == (57, 1)
        assert (res.start, res.length) == (58, 6)
        assert "default full scale" in msg.comment
    fsm = db.get_message_by_frame_id(BASE + 4)
    assert fsm.is_multiplexed()
    group = fsm.get_signal_by_name("Group")
    assert group.is_multiplexer and (group.start, group.length) == (0, 8)
    assert {int(k): str(v) for k, v in group.choices.items()} == {
        0: "force", 1: "moment", 2: "linear", 3: "angular"}
    reserved = fsm.get_signal_by_name("Reserved")
    assert (reserved.start, reserved.length) == (8, 8)
    for i, g in enumerate(GROUPS):
        for k, axis in enumerate("XYZ"):
            s = fsm.get_signal_by_name(f"FullScale_{g}_{axis}")
            assert s.multiplexer_ids == [i]
            assert (s.start, s.length, s.byte_order, s.is_signed) == (16 + 16 * k, 16,
                                                                     "little_endian", False)
            assert s.scale == FS_UNIT[g]
    # The database comment warns that the factors are the defaults only.
    raw = DBC_PATH.read_text()
    assert re.search(r'CM_ "[^"]*DEFAULT full scales[^"]*configuration[^"]*can change', raw)


def random_sample(rng: random.Random, saturate: bool):
    values = []
    for g in GROUPS:
        for _ in range(3):
            lim = (2.6 if saturate else 1.99) * FULL_SCALE[g]
            values.append(rng.uniform(-lim, lim))
    return values


def test_c_encoder_decoded_by_cantools(db):
    rng = random.Random(20240601)
    samples = []
    commands = []
    for i in range(1500):
        saturate = i % 10 == 9
        fault = rng.randrange(16) if i % 7 == 3 else 0
        values = random_sample(rng, saturate)
        t_us = 1_700_000_000_000_000 + 1000 * i + rng.randrange(1000)
        seq = i % 256
        samples.append((t_us, seq, fault, values))
        commands.append(f"S {t_us} {seq} {fault} " + " ".join(repr(v) for v in values))
    lines = run_encoder(commands)
    assert len(lines) == 4 * len(samples)

    n_saturated = 0
    for n, (t_us, seq, fault, values) in enumerate(samples):
        for gi, g in enumerate(GROUPS):
            t, ifname, frame_id, extended, data = parse_line(lines[4 * n + gi])
            assert (t, ifname, frame_id, extended, len(data)) == (t_us, "vcan0", BASE + gi,
                                                                 False, 8)
            dec = db.decode_message(frame_id, data, decode_choices=False)
            count = FULL_SCALE[g] / 16384
            saturated = False
            for k, axis in enumerate("XYZ"):
                want = values[3 * gi + k]
                got = dec[f"{g}_{axis}"]
                lo, hi = -32768 * count, 32767 * count
                if want > hi + 0.5 * count or want < lo - 0.5 * count:
                    # Out of the int16 range: clamped to the end it passed.
                    saturated = True
                    assert got == pytest.approx(hi if want > 0 else lo, rel=1e-12)
                else:
                    # Rounded to the nearest count (so within one count).
                    assert abs(got - want) <= 0.5 * count * (1 + 1e-9), (g, axis, want, got)
            n_saturated += saturated
            assert dec["Saturated"] == int(saturated), (n, g)
            assert dec["Fault"] == (fault >> gi) & 1
            assert dec["Sequence"] == seq
            assert dec["StatusReserved"] == 0
    assert n_saturated > 100  # the saturated branch was exercised


def test_full_scale_frame_decoded_by_cantools(db):
    cases = [(0, [200.0, 150.04, 6553.5]), (1, [12.0, 0.01, 655.35]),
             (2, [98.1, 9.81, 50.0]), (3, [1000.0, 0.1, 6553.4])]
    lines = run_encoder([f"F {1000 + g} {g} " + " ".join(repr(x) for x in fs)
                         for g, fs in cases])
    assert len(lines) == len(cases)
    for (g, fs), line in zip(cases, lines):
        t, _, frame_id, _, data = parse_line(line)
        assert (t, frame_id, data[0], data[1]) == (1000 + g, BASE + 4, g, 0)
        dec = db.decode_message(frame_id, data)
        assert str(dec["Group"]) == GROUPS[g].lower()
        unit = FS_UNIT[GROUPS[g]]
        for k, axis in enumerate("XYZ"):
            want = round(fs[k] / unit) * unit
            assert dec[f"FullScale_{GROUPS[g]}_{axis}"] == pytest.approx(want, rel=1e-12)


def test_candump_lines_read_by_other_parsers(tmp_path):
    rng = random.Random(7)
    commands = [f"S {1_700_000_000_000_000 + 997 * i} {i % 256} 0 "
                + " ".join(repr(v) for v in random_sample(rng, False)) for i in range(50)]
    lines = run_encoder(commands)
    ours = [parse_line(line) for line in lines]

    # cantools' candump log reader.
    parsed = list(cantools.logreader.Parser(io.StringIO("\n".join(lines) + "\n")))
    assert len(parsed) == len(ours)
    for (t_us, _, frame_id, _, data), frame in zip(ours, parsed):
        assert frame.frame_id == frame_id and bytes(frame.data) == data
        assert frame.timestamp.timestamp() == pytest.approx(t_us * 1e-6, abs=2e-6)

    # can-utils' own reader of the format (log2asc), when installed.
    log2asc = shutil.which("log2asc")
    if log2asc is None:
        pytest.skip("log2asc (can-utils) not installed")
    log = tmp_path / "can.log"
    log.write_text("\n".join(lines) + "\n")
    asc = tmp_path / "can.asc"
    subprocess.run([log2asc, "-I", str(log), "-O", str(asc), "vcan0"], check=True, timeout=60)
    rows = re.findall(r"^\s*(\d+\.\d+)\s+1\s+([0-9A-F]+)\s+Rx\s+d\s+8\s+((?:[0-9A-F]{2}\s?)+)$",
                      asc.read_text(), flags=re.M)
    assert len(rows) == len(ours)
    t0 = ours[0][0]
    for (t_us, _, frame_id, _, data), (t_rel, rid, rdata) in zip(ours, rows):
        assert int(rid, 16) == frame_id
        assert bytes.fromhex(rdata.replace(" ", "")) == data
        assert abs(float(t_rel) - (t_us - t0) * 1e-6) < 2e-6
