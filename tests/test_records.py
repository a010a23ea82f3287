"""Bench-record loader: good records read with their conditions; bad ones name file, row, problem."""
from pathlib import Path

import numpy as np
import pytest

from dynamics.records import RecordError, parse_column_map, read_record, write_record

MEASURED = Path(__file__).parents[2] / "shared" / "measured"


def _record(tmp_path, name="r.csv", n=400, revs=1.0, direction=1, torque=100.0, header=None,
            mutate=None, comments=("encoder_zero: s1",)):
    th_out = direction * np.linspace(0.0, 360.0 * revs, n)
    t = np.linspace(0.0, 2.0, n)
    cols = [t, 81.0 * th_out, th_out, np.full(n, direction * torque)]
    if mutate:
        mutate(cols)
    p = tmp_path / name
    write_record(p, *cols, comments=list(comments), extra={"oil_C": np.full(n, 25.0)})
    if header is not None:
        text = p.read_text().splitlines()
        k = next(i for i, ln in enumerate(text) if not ln.startswith("#"))
        text[k] = header
        p.write_text("\n".join(text) + "\n")
    return p


def test_a_good_record_reads_with_its_conditions_and_comments(tmp_path):
    r = read_record(_record(tmp_path, direction=-1, torque=300.0))
    assert r.direction == -1 and r.torque_Nm == -300.0
    # 81 x 360 deg of input in 2 s = 14.58 turns/s = 874.8 rpm (exact by construction)
    assert r.input_speed_rpm == pytest.approx(81 * 360 / 2.0 / 6.0, rel=1e-6)   # 10-digit values
    assert r.encoder_zero == "s1" and "oil_C" in r.extra


@pytest.mark.parametrize("mutate,needle", [
    # data row k is file line k + 3 (one comment, one header)
    (lambda c: c[2].__setitem__(7, np.nan), "row 10: output_angle_deg = 'nan'"),
    (lambda c: c[0].__setitem__(9, c[0][8]), "row 12: time_s"),
    (lambda c: c[2].__setitem__(slice(200, None), c[2][200:] - 360.0), "row 203: output_angle_deg jumps by -359"),
])
def test_a_bad_value_is_reported_with_file_and_row(tmp_path, mutate, needle):
    p = _record(tmp_path, mutate=mutate)
    with pytest.raises(RecordError) as e:
        read_record(p)
    assert str(p) in str(e.value) and needle in str(e.value)


def test_a_non_numeric_value_is_named(tmp_path):
    p = _record(tmp_path)
    lines = p.read_text().splitlines()
    cells = lines[10].split(",")
    lines[10] = ",".join(cells[:3] + ["abc"] + cells[4:])
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordError, match=r"row 11: output_torque_Nm = 'abc' is not a number"):
        read_record(p)


def test_a_missing_column_is_named_and_never_guessed(tmp_path):
    p = _record(tmp_path, header="t,input_angle_deg,output_angle_deg,output_torque_Nm,oil_C")
    with pytest.raises(RecordError, match=r"missing column 'time_s'.*column map"):
        read_record(p)
    r = read_record(p, parse_column_map("time_s=t"))
    assert r.time_s[-1] == pytest.approx(2.0)


def test_a_headerless_record_needs_indices(tmp_path):
    p = _record(tmp_path)
    body = [ln for ln in p.read_text().splitlines() if not ln.startswith("#")][1:]
    q = tmp_path / "noheader.csv"
    q.write_text("\n".join(body) + "\n")
    with pytest.raises(RecordError, match="headerless record needs a 0-based column index"):
        read_record(q, header=False)
    r = read_record(q, parse_column_map("time_s=0,input_angle_deg=1,output_angle_deg=2,output_torque_Nm=3"),
                    header=False)
    assert len(r.time_s) == 400


def test_less_than_one_output_revolution_is_refused(tmp_path):
    with pytest.raises(RecordError, match=r"turns 342.00 deg.*at least one output revolution"):
        read_record(_record(tmp_path, revs=0.95))


def test_a_record_one_sample_short_of_a_revolution_is_accepted(tmp_path):
    # a bench sampling one revolution: n samples span n - 1 steps (the real records do this)
    r = read_record(_record(tmp_path, n=400, revs=399 / 400))
    assert r.output_travel_deg == pytest.approx(359.1)


def test_the_real_bench_records_load():
    if not MEASURED.is_dir():
        pytest.skip(f"{MEASURED} absent: the real bench records are not in this checkout")
    r = read_record(MEASURED / "rv160n_1800rpm_300Nm_25C_bw.csv")
    # README: 1800 rpm input, 300 N.m resisting a backward run, 0.25 ms sampling, 1 revolution
    assert r.direction == -1 and r.torque_Nm == -300.0
    assert r.input_speed_rpm == pytest.approx(1800.0, rel=2e-3)
    assert len(r.time_s) == 10800 and r.comments[0].startswith("Real bench record")


# ------------------------------------------------------------------ paths that are no text record
ALLOWED = "a record is a UTF-8 text CSV with the header time_s,input_angle_deg,output_angle_deg,output_torque_Nm"


def _one_line_naming(exc, path, what):
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg and what in msg and ALLOWED in msg, msg


def test_a_folder_given_as_a_record_is_refused_in_one_line(tmp_path):
    with pytest.raises(RecordError) as e:
        read_record(tmp_path)
    _one_line_naming(e, tmp_path, "is a folder")


def test_an_unreadable_record_is_refused_in_one_line(tmp_path, monkeypatch):
    p = _record(tmp_path)
    # chmod 000 does not stop root (the CI container): make the read itself fail as it would
    real = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda self: (_ for _ in ()).throw(
        PermissionError(13, "Permission denied")) if self == p else real(self))
    with pytest.raises(RecordError) as e:
        read_record(p)
    _one_line_naming(e, p, "permission denied")


def test_a_binary_file_is_refused_even_when_it_decodes_as_utf8(tmp_path):
    p = tmp_path / "zeros.csv"
    p.write_bytes(b"time_s,input_angle_deg\n" + b"\0" * 64)     # NUL bytes are valid UTF-8
    with pytest.raises(RecordError) as e:
        read_record(p)
    _one_line_naming(e, p, "binary content (NUL byte at offset 23)")
    q = tmp_path / "picture.csv"
    q.write_bytes(bytes(range(256)))
    with pytest.raises(RecordError) as e:
        read_record(q)
    _one_line_naming(e, q, "binary content")


def test_a_latin1_record_is_refused_naming_the_byte_and_the_fix(tmp_path):
    p = _record(tmp_path, comments=("oil at 25 °C",))
    p.write_bytes(p.read_text().encode("latin-1"))
    with pytest.raises(RecordError) as e:
        read_record(p)
    _one_line_naming(e, p, "not UTF-8 text (byte 0xb0 at offset")
    assert "re-save it as UTF-8" in str(e.value)


def test_a_spreadsheet_byte_order_mark_is_not_part_of_the_header(tmp_path):
    p = _record(tmp_path, comments=())
    p.write_bytes(b"\xef\xbb\xbf" + p.read_bytes())
    assert read_record(p).time_s[-1] == pytest.approx(2.0)


def test_a_record_larger_than_the_cap_is_refused_before_it_is_read(tmp_path, monkeypatch):
    import dynamics.records as records
    p = _record(tmp_path)
    monkeypatch.setattr(records, "RECORD_MAX_BYTES", 100)     # a 30 GB file read whole ran out of memory
    monkeypatch.setattr(Path, "read_bytes", lambda self: pytest.fail("read before its size was checked"))
    with pytest.raises(RecordError) as e:
        read_record(p)
    _one_line_naming(e, p, "a record file has at most 100 bytes")
