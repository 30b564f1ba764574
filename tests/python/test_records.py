"""Ground-motion records: the readers (AT2, one and two columns, arrays), their errors (file and
line named), the record as a signal (linear between samples, zero after), records in scenes."""

import copy
import os
import pickle

import numpy as np
import pytest

import nvib
from nvib import GroundMotion, RecordError

VALUES = [0.0, 0.0125, -0.031, 0.047, -0.0205, 0.0089, 0.0]  # in g


def write(path, text):
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)
    return str(path)


def at2(tmp_path, values=VALUES, header="NPTS=    {n}, DT=   .0100 SEC", per_line=5, name="rec.AT2"):
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD",
             "Test event 2026, Test station, 090",
             "ACCELERATION TIME SERIES IN UNITS OF G",
             header.format(n=len(values))]
    for k in range(0, len(values), per_line):
        lines.append("".join(f"{v:15.7E}" for v in values[k:k + per_line]))
    return write(tmp_path / name, "\n".join(lines) + "\n")


# ---- AT2 ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("header", ["NPTS=    {n}, DT=   .0100 SEC", "   {n}   0.0100   NPTS, DT"])
def test_at2_both_header_styles(tmp_path, header):
    gm = GroundMotion.from_at2(at2(tmp_path, header=header))
    np.testing.assert_array_equal(gm.a, VALUES)
    np.testing.assert_allclose(gm.t, 0.01 * np.arange(len(VALUES)), rtol=0, atol=1e-15)
    assert gm.dt == pytest.approx(0.01, rel=1e-12)
    assert gm.pga == 0.047 and gm.duration == pytest.approx(0.06, rel=1e-12)
    assert gm.units == "g" and gm.name == "rec.AT2" and len(gm) == len(VALUES)
    assert "7 samples" in repr(gm) and "pga=0.047 g" in repr(gm)


def test_at2_scale_to_si(tmp_path):
    gm = GroundMotion.from_at2(at2(tmp_path), scale=nvib.STANDARD_GRAVITY)
    np.testing.assert_array_equal(gm.a, np.array(VALUES) * 9.80665)
    assert gm.units == "m/s^2"  # g times the standard gravity
    assert GroundMotion.from_at2(at2(tmp_path), scale=0.5).units == "g"  # an intensity level: still in g
    assert GroundMotion.from_file(at2(tmp_path)) == GroundMotion.from_at2(at2(tmp_path))  # by its extension


def test_at2_errors_name_file_and_line(tmp_path):
    path = write(tmp_path / "noheader.AT2", "title\nevent\nunits\nnothing here\n 0.1 0.2\n")
    with pytest.raises(RecordError, match=r"noheader.AT2, line 4: no NPTS and DT") as exc:
        GroundMotion.from_at2(path)
    assert exc.value.line == 4 and exc.value.path == path

    path = at2(tmp_path, header="NPTS=    {n}, DT=   .0100 SEC".replace("{n}", "9"), name="short.AT2")
    with pytest.raises(RecordError, match=r"short.AT2, line 4: the header says NPTS = 9, but 7 values follow it "
                                          r"\(lines 5 to 6\)"):
        GroundMotion.from_at2(path)

    path = at2(tmp_path, name="bad.AT2")
    with open(path, encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    lines[5] = lines[5][:15] + "  abc"
    write(path, "\n".join(lines) + "\n")
    with pytest.raises(RecordError, match=r"bad.AT2, line 6: 'abc' is not a number") as exc:
        GroundMotion.from_at2(path)
    assert exc.value.line == 6

    with pytest.raises(RecordError, match="no such file"):
        GroundMotion.from_at2(tmp_path / "missing.AT2")
    path = at2(tmp_path, header="NPTS=    {n}, DT=   0.0 SEC", name="zerodt.AT2")
    with pytest.raises(RecordError, match=r"line 4: DT = 0.0 must be > 0"):
        GroundMotion.from_at2(path)


# Records as they are found in the wild: the header forms PEER has used, line ends changed by copies
# between systems, Fortran exponents and fixed columns.
NORTHRIDGE = [0.0, -0.1826520e-3, 0.2241389e-2, -0.1234567e-1, 0.8437e-1, -0.5678901e-3, 0.0]


def columns(values, fmt="{:15.7E}", per_line=5):
    return ["".join(fmt.format(v) for v in values[k:k + per_line]) for k in range(0, len(values), per_line)]


def peer_written(values, per_line=5):
    """Values as PEER writes them, E15.7 without a leading zero: '  -.1826520E-03'."""
    def one(v):
        text = f"{v:.6E}"  # -1.826520E-04 -> -.1826520E-03
        sign = "-" if text.startswith("-") else ""
        mantissa, exp = text.lstrip("-").split("E")
        return f"{sign}.{mantissa.replace('.', '')}E{int(exp) + 1:+03d}".rjust(15) if v else "   .0000000E+00"
    return ["".join(one(v) for v in values[k:k + per_line]) for k in range(0, len(values), per_line)]


def write_bytes(path, lines, end):
    with open(path, "wb") as fh:
        fh.write(end.join(lines).encode() + end.encode())
    return str(path)


def test_northridge_with_cr_cr_lf_line_ends_is_read(tmp_path):
    """A PEER/OpenSees Northridge file copied through a text-mode transfer ends its lines with CR CR LF. It
    used to be refused, the error blaming a header line; every line end now counts as one."""
    header = ["PEER NGA STRONG MOTION DATABASE RECORD",
              "Northridge-01, 1/17/1994, Sylmar - Olive View Med FF, 360",
              "ACCELERATION TIME SERIES IN UNITS OF G",
              f"NPTS=  {len(NORTHRIDGE)}, DT=   .0200 SEC,"]
    for end in ("\r\r\n", "\r\n", "\n", "\r"):
        path = write_bytes(tmp_path / "RSN1086_NORTHR_SYL360.AT2", header + peer_written(NORTHRIDGE) + ["", ""], end)
        gm = GroundMotion.from_at2(path)
        np.testing.assert_allclose(gm.a, NORTHRIDGE, rtol=1e-15, atol=0)
        assert gm.dt == pytest.approx(0.02, rel=1e-12) and len(gm) == len(NORTHRIDGE) and gm.units == "g"
        assert (gm.event, gm.date, gm.station, gm.component, gm.rsn) == (
            "Northridge-01", "1/17/1994", "Sylmar - Olive View Med FF", "360", 1086)
        assert gm.label == "RSN1086, Northridge-01, Sylmar - Olive View Med FF, 360"
        assert gm.name == "RSN1086_NORTHR_SYL360.AT2" and "Sylmar" in repr(gm)
    # a bad sample is blamed on its own line, counted as an editor counts them, never on the header
    bad = peer_written(NORTHRIDGE)
    bad[1] = bad[1][:15] + "  x.1E-02"
    path = write_bytes(tmp_path / "bad.AT2", header + bad, "\r\r\n")
    with pytest.raises(RecordError, match=r"bad.AT2, line 6: 'x.1E-02' is not a number"):
        GroundMotion.from_at2(path)


@pytest.mark.parametrize("line4", ["NPTS=  7, DT= .0100 SEC", "NPTS=7,DT=.01", "npts = 7 , dt = 0.0100 sec",
                                   "NPTS=     7, DT=   .0100 SEC,", "   7   .0100   NPTS, DT",
                                   "7 0.01 NPTS, DT, SEC", "DT= .0100 SEC, NPTS= 7"])
def test_old_and_new_peer_headers(tmp_path, line4):
    path = write_bytes(tmp_path / "h.AT2", ["PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.",
                                            "NORTHRIDGE EQ 01/17/94, 1231, SYLMAR COUNTY HOSP PARKING LOT, 360",
                                            "ACCELERATION TIME HISTORY IN UNITS OF G", line4]
                       + columns(NORTHRIDGE, "{:15.5E}"), "\n")
    gm = GroundMotion.from_at2(path)
    np.testing.assert_allclose(gm.a, NORTHRIDGE, rtol=1e-5)
    assert gm.dt == pytest.approx(0.01, rel=1e-12) and gm.units == "g"
    assert (gm.event, gm.date, gm.station, gm.component, gm.rsn) == (
        "NORTHRIDGE EQ", "01/17/94", "SYLMAR COUNTY HOSP PARKING LOT", "360", None)
    assert gm.label == "NORTHRIDGE EQ, SYLMAR COUNTY HOSP PARKING LOT, 360"


def test_fortran_numbers_and_fixed_columns(tmp_path):
    """D exponents, mantissas without a leading digit, and values that fill their fixed-width column so no
    blank separates them from the next one."""
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", "Kobe, Japan, 1/16/1995, KJMA, 000",
             "ACCELERATION TIME SERIES IN UNITS OF G", "NPTS=  7, DT=   .0050 SEC,",
             "0.0D+00 -.1826520E-03 .2241389D-02",
             "-0.1234567E-01-0.8437000E-01+0.5678901E-03",  # run together: E15.7 with a leading zero fills it
             "0.0", "   ", ""]
    gm = GroundMotion.from_at2(write_bytes(tmp_path / "kobe.AT2", lines, "\r\n"))
    np.testing.assert_allclose(gm.a, [0.0, -0.1826520e-3, 0.2241389e-2, -0.1234567e-1, -0.8437e-1, 0.5678901e-3,
                                      0.0], rtol=1e-15)
    assert gm.dt == 0.005
    # "Kobe, Japan" has a comma of its own: the date is found after it
    assert (gm.event, gm.date, gm.station, gm.component) == ("Kobe, Japan", "1/16/1995", "KJMA", "000")
    lines[5] = "-0.1234567E-01-0.84.37000E-01"  # not two numbers: named as it is
    with pytest.raises(RecordError, match=r"line 6: '-0.84.37000E-01' is not a number"):
        GroundMotion.from_at2(write_bytes(tmp_path / "bad.AT2", lines, "\n"))


def test_a_record_in_g_stays_in_g_at_any_scale(tmp_path):
    gm = GroundMotion.from_at2(at2(tmp_path))
    for f in (0.5, 2.0, 3.7, -1.0):
        assert gm.scaled(f).units == "g" and GroundMotion.from_at2(at2(tmp_path), scale=f).units == "g"
    si = gm.scaled(nvib.STANDARD_GRAVITY)
    assert si.units == "m/s^2" and si.scaled(1.0 / nvib.STANDARD_GRAVITY).units == "g"
    assert si.scaled(2.0).units == "m/s^2"
    assert gm.scaled(2.0).label == gm.label and gm.scaled(2.0).component == "090"
    one = write(tmp_path / "one.txt", "\n".join(str(v) for v in VALUES))
    assert GroundMotion.from_file(one, dt=0.01, units="m/s^2").scaled(3.0).units == "m/s^2"
    assert GroundMotion.from_file(one, dt=0.01).units == ""  # a plain file says nothing of its unit
    with pytest.raises(nvib.ArgumentError, match="an AT2 file is in g") as exc:
        GroundMotion.from_file(at2(tmp_path), units="m/s^2")
    assert exc.value.argument == "units"


def test_scaled_to_sa_matches_the_exact_spectrum(tmp_path):
    """Sa(T1) from the exact elastic spectrum (nvib._core); the scaled record has that PSa at T1."""
    from nvib.analysis.spectrum import exact_sdof_peaks

    t = np.arange(0, 4.0, 0.01)
    gm = GroundMotion.from_array(np.sin(5 * t) * np.exp(-0.3 * t), dt=0.01, units="g", name="pulse")
    sd, _ = exact_sdof_peaks(np.arange(0, 12.0, 0.0025), gm(np.arange(0, 12.0, 0.0025)), [0.8], 0.05)
    assert gm.psa(0.8) == pytest.approx(sd[0] * (2 * np.pi / 0.8) ** 2, rel=1e-3)
    scaled, factor = gm.scaled_to_sa(0.8, 0.3)
    assert factor == pytest.approx(0.3 / gm.psa(0.8), rel=1e-14)
    assert scaled.psa(0.8) == pytest.approx(0.3, rel=1e-12) and scaled.units == "g"
    np.testing.assert_allclose(scaled.a, gm.a * factor, rtol=1e-15)
    s2, f2 = gm.scaled_to_sa(0.8, 0.3, damping=0.02)
    assert s2.psa(0.8, damping=0.02) == pytest.approx(0.3, rel=1e-12) and f2 < factor
    uneven = GroundMotion(np.r_[0.0, np.cumsum(np.full(399, 0.01) * (1 + 0.1 * (np.arange(399) % 2)))],
                          np.sin(5 * t) * np.exp(-0.3 * t))
    assert uneven.dt is None and uneven.psa([0.5, 1.0]).shape == (2,)
    for bad, argument in (((0.0, 1.0), "period"), ((1.0, -1.0), "value")):
        with pytest.raises(nvib.ArgumentError) as exc:
            gm.scaled_to_sa(*bad)
        assert exc.value.argument == argument
    with pytest.raises(nvib.ArgumentError, match="PSa at T = 1 s is 0") as exc:
        GroundMotion.from_array([0.0, 0.0, 0.0], dt=0.01).scaled_to_sa(1.0, 0.5)
    assert exc.value.argument == "period"


@pytest.mark.skipif(os.name != "posix", reason="symbolic links, /dev/zero and pipes")
def test_files_that_cannot_be_read_are_refused_before_reading(tmp_path):
    """A loop of symbolic links, a link to nothing, a folder and a device (/dev/zero would be read until the
    memory runs out) are RecordErrors naming the file; a file over MAX_RECORD_BYTES is refused from its
    size, a pipe from what it gave; a pipe that ends is read."""
    from nvib._records import MAX_RECORD_BYTES

    (tmp_path / "a").symlink_to(tmp_path / "b")
    (tmp_path / "b").symlink_to(tmp_path / "a")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    (tmp_path / "folder").mkdir()
    for path, reason in ((tmp_path / "a", "a loop of symbolic links"), (tmp_path / "dangling", "which does not exist"),
                         (tmp_path / "folder", "is a folder, not a record file"),
                         ("/dev/zero", "is a device, not a record file")):
        with pytest.raises(RecordError, match=reason) as exc:
            GroundMotion.from_file(path, dt=0.01)
        assert exc.value.path == str(path) and exc.value.line is None
    huge = tmp_path / "huge.txt"
    with open(huge, "wb") as fh:  # sparse: 65 MiB on paper
        fh.write(b"0.0\n1.0\n")
        fh.truncate(MAX_RECORD_BYTES + 2**20)
    with pytest.raises(RecordError, match="65.0 MB, more than the 64 MB a record file may have"):
        GroundMotion.from_file(huge, dt=0.01)
    read, write_end = os.pipe()
    os.write(write_end, b"0.0\n1.0\n-1.0\n")
    os.close(write_end)
    try:
        assert len(GroundMotion.from_file(f"/dev/fd/{read}", dt=0.01)) == 3
    finally:
        os.close(read)


# ---- plain files and arrays ----------------------------------------------------------------------

def test_one_and_two_columns(tmp_path):
    one = write(tmp_path / "one.txt", "# a in m/s^2\n" + "\n".join(str(v) for v in VALUES) + "\n")
    gm = GroundMotion.from_file(one, dt=0.02, scale=2.0)
    np.testing.assert_array_equal(gm.a, np.array(VALUES) * 2.0)
    assert gm.dt == pytest.approx(0.02) and gm.t[0] == 0.0
    with pytest.raises(nvib.ArgumentError, match="give their time step dt") as exc:
        GroundMotion.from_file(one)
    assert exc.value.argument == "dt"

    t = [0.0, 0.01, 0.03, 0.06]
    two = write(tmp_path / "two.csv", "\n".join(f"{a}, {b}" for a, b in zip(t, VALUES)) + "\n")
    gm = GroundMotion.from_file(two)
    np.testing.assert_array_equal(gm.t, t)
    assert gm.dt is None  # uneven steps
    with pytest.raises(nvib.ArgumentError, match="its times are given"):
        GroundMotion.from_file(two, dt=0.01)

    ragged = write(tmp_path / "ragged.txt", "0 1\n0.1 2\n0.2\n")
    with pytest.raises(RecordError, match=r"ragged.txt, line 3: expected 2 columns as on line 1, got 1"):
        GroundMotion.from_file(ragged)
    backwards = write(tmp_path / "back.txt", "0 1\n0.2 2\n0.1 3\n")
    with pytest.raises(RecordError, match="times must increase strictly"):
        GroundMotion.from_file(backwards)
    word = write(tmp_path / "word.txt", "1\n2\nx3\n")
    with pytest.raises(RecordError, match=r"word.txt, line 3: 'x3' is not a number"):
        GroundMotion.from_file(word, dt=0.1)


def test_from_array_scaled_and_values():
    gm = GroundMotion.from_array([0.0, 1.0, -2.0], dt=0.5, t0=1.0, name="a")
    np.testing.assert_array_equal(gm.t, [1.0, 1.5, 2.0])
    half = gm.scaled(0.5)
    np.testing.assert_array_equal(half.a, [0.0, 0.5, -1.0])
    assert half.pga == 1.0 and gm.pga == 2.0  # the original is unchanged
    # linear between samples, zero outside the record
    np.testing.assert_array_equal(gm([0.5, 1.25, 1.75, 2.0, 2.5]), [0.0, 0.5, -0.5, -2.0, 0.0])
    with pytest.raises(nvib.ArgumentError) as exc:
        GroundMotion.from_array([1.0, 2.0], dt=-1.0)
    assert exc.value.argument == "dt"
    with pytest.raises(nvib.ArgumentError) as exc:
        GroundMotion.from_array([1.0, np.nan], dt=0.1)
    assert exc.value.argument == "a"


def test_pickle_and_copy_round_trip(tmp_path):
    gm = GroundMotion.from_at2(at2(tmp_path))
    for other in (pickle.loads(pickle.dumps(gm)), copy.copy(gm), copy.deepcopy(gm)):
        assert other == gm and other is not gm


# ---- a record as the ground motion of a model ------------------------------------------------------

def free_mass(signal):
    return nvib.Model([2.0, 3.0], effects=[{"type": "ground_acceleration", "signal": signal}])


@pytest.mark.parametrize("dt", [0.01, 0.004])
def test_free_mass_follows_the_record_then_floats(dt):
    """A free mass under a ground acceleration has a = -a_g(t) exactly: the record interpolated
    linearly between samples, and zero after its last sample, when the velocity stays constant."""
    gm = GroundMotion.from_array(VALUES, dt=0.01, scale=9.80665)
    res = nvib.solve(free_mass(gm), nvib.CentralDifference(), dt=dt, t_end=0.12)
    for j in range(2):
        np.testing.assert_allclose(res.a[:, j], -gm(res.t), rtol=0, atol=1e-13 * gm.pga)
    after = res.t > gm.t[-1] + 1e-12
    assert after.sum() >= 5
    np.testing.assert_array_equal(res.a[after], 0.0)
    assert np.all(res.v[after] == res.v[after][0])  # free flight at constant velocity


def test_record_equals_its_table():
    gm = GroundMotion.from_array(VALUES, dt=0.01)
    a = nvib.solve(free_mass(gm), nvib.CEMDTS(), dt=0.003, t_end=0.1)
    b = nvib.solve(free_mass({"kind": "table", "t": gm.t.tolist(), "values": VALUES}), nvib.CEMDTS(), dt=0.003,
                   t_end=0.1)
    np.testing.assert_array_equal(a.u, b.u)


SCENE = """
[scene]
name = "sdof_record"
t_end = 0.2
dt = 0.001

[dofs]
names = ["x"]
mass = [1e3]

[[effect]]
type = "spring"
measure = {{ x = 1.0 }}
k = 4e5

[[effect]]
type = "ground_acceleration"
signal = {signal}
"""


def test_scene_reads_record_relative_to_its_file(tmp_path, monkeypatch):
    sub = tmp_path / "scenes"
    sub.mkdir()
    at2(sub, name="quake.AT2")
    scene = write(sub / "sdof.toml", SCENE.format(signal='{ kind = "record", file = "quake.AT2", scale = 9.80665 }'))
    monkeypatch.chdir(tmp_path)  # the record is found next to the scene, not in the working directory
    model = nvib.load_scene(scene)
    direct = nvib.Model([1e3], effects=[
        {"type": "spring", "measure": {0: 1.0}, "k": 4e5},
        {"type": "ground_acceleration", "signal": GroundMotion.from_at2(sub / "quake.AT2", scale=9.80665)}])
    a = nvib.solve(model, nvib.Newmark(), dt=1e-3, t_end=0.2)
    b = nvib.solve(direct, nvib.Newmark(), dt=1e-3, t_end=0.2)
    np.testing.assert_array_equal(a.u, b.u)
    assert np.max(np.abs(a.u)) > 0


def test_scene_with_a_bad_record_names_it(tmp_path):
    scene = write(tmp_path / "s.toml", SCENE.format(signal='{ kind = "record", file = "nowhere.AT2" }'))
    with pytest.raises(nvib.SceneError, match=r"s.toml: .*nowhere.AT2: no such file"):
        nvib.load_scene(scene)
    at2(tmp_path, name="one.txt", header="x")  # not an AT2 by name: read as columns, and the header is text
    scene = write(tmp_path / "t.toml", SCENE.format(signal='{ kind = "record", file = "one.txt", dt = 0.01 }'))
    with pytest.raises(nvib.SceneError, match=r"one.txt, line 1: expected one column \(a\) or two"):
        nvib.load_scene(scene)


def test_absolute_acceleration_of_a_free_mass_is_zero():
    """A free mass moves with the ground: its relative acceleration is -a_g, its absolute one 0. With the
    ground acting on one DOF only (a measure), the other DOF's absolute acceleration is its relative one."""
    gm = GroundMotion.from_array(VALUES, dt=0.01, scale=9.80665)
    res = nvib.solve(free_mass(gm), nvib.CentralDifference(), dt=0.004, t_end=0.12)
    assert np.max(np.abs(res.a)) > 0.3  # the record moves it (pga 0.46 m/s², sampled every 4 ms)
    np.testing.assert_allclose(res.absolute_a, 0.0, atol=1e-15 * gm.pga)
    one = nvib.Model([2.0, 3.0], effects=[{"type": "ground_acceleration", "measure": {1: 1.0}, "signal": gm}])
    res = nvib.solve(one, nvib.CEMDTS(), dt=0.004, t_end=0.12, dofs=[1, 0])
    np.testing.assert_allclose(res.absolute_a[:, 0], 0.0, atol=1e-15 * gm.pga)
    np.testing.assert_array_equal(res.absolute_a[:, 1], res.a[:, 1])
    back = pickle.loads(pickle.dumps(res))
    np.testing.assert_array_equal(back.absolute_a, res.absolute_a)
    still = nvib.solve(nvib.Model([1.0], u0=[1.0], effects=[{"type": "spring", "measure": {0: 1.0}, "k": 1.0}]),
                       nvib.CEMDTS(), dt=0.01, t_end=0.1)
    assert still.absolute_a is still.a or np.array_equal(still.absolute_a, still.a)  # no ground: relative = absolute


def test_shipped_record_is_what_its_generator_makes():
    """The synthetic record SGM-1 shipped for the inelastic scenes is reproducible from its seed."""
    import subprocess
    import sys

    script = os.path.join(os.path.dirname(__file__), "..", "..", "tools", "make_ground_motion.py")
    record = os.path.join(os.path.dirname(nvib.__file__), "scenes", "records", "sgm1.AT2")
    run = subprocess.run([sys.executable, script, "--check", "--out", record], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    gm = nvib.GroundMotion.from_at2(record)
    assert len(gm.t) == 3001 and gm.dt == pytest.approx(0.01) and gm.pga == pytest.approx(0.40, rel=1e-6)


# ---- a scene under another record: load_scene(ground_motion=) and nvib run --record ----------------

def northridge_like(tmp_path, scale=1.0):
    """A PEER-like file with CR CR LF line ends: a decaying 2 Hz pulse train in g, 0.01 s apart."""
    t = np.arange(0, 3.0, 0.01)
    a = scale * 0.3 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-t)
    header = ["PEER NGA STRONG MOTION DATABASE RECORD", "Northridge-01, 1/17/1994, Sylmar - Olive View Med FF, 360",
              "ACCELERATION TIME SERIES IN UNITS OF G", f"NPTS=  {t.size}, DT=   .0100 SEC,"]
    return write_bytes(tmp_path / "RSN1086_NORTHR_SYL360.AT2", header + peer_written(list(a)), "\r\r\n")


def test_load_scene_under_another_record(tmp_path):
    """The record replaces the scene's ground motion, in m/s^2 (a record in g is converted); a scene without
    one is refused naming ground_motion."""
    gm = GroundMotion.from_at2(northridge_like(tmp_path))
    model = nvib.load_scene("building_inelastic", ground_motion=gm)
    si = nvib.load_scene("building_inelastic", ground_motion=gm.scaled(nvib.STANDARD_GRAVITY))
    a = nvib.solve(model, nvib.Newmark(), dt=0.005, t_end=1.0)
    b = nvib.solve(si, nvib.Newmark(), dt=0.005, t_end=1.0)
    own = nvib.solve(nvib.load_scene("building_inelastic"), nvib.Newmark(), dt=0.005, t_end=1.0)
    np.testing.assert_array_equal(a.u, b.u)
    assert not np.array_equal(a.u, own.u) and np.max(np.abs(a.u)) > 0
    for scene, without, match in (("pendulum", (), r"no ground_acceleration effect\)"),
                                  ("building", ("ground",), "left out by without")):
        with pytest.raises(nvib.ArgumentError, match=match) as exc:
            nvib.load_scene(scene, ground_motion=gm, without=without)
        assert exc.value.argument == "ground_motion"
    with pytest.raises(TypeError, match="expected a GroundMotion"):
        nvib.load_scene("building", ground_motion=[0.0, 1.0])


def test_run_under_a_record_scaled_to_sa(tmp_path, capsys):
    from _cli import run_cli

    path = northridge_like(tmp_path)
    gm = GroundMotion.from_at2(path)
    code, out, err = run_cli(capsys, "run", "building_inelastic", "--record", path, "--sa", "0.9", "0.5", "--t-end",
                             "1", "--scheme", "newmark", "--out", tmp_path / "r.npz")
    assert code == 0, err
    scaled, factor = gm.scaled_to_sa(0.9, 0.5)
    line = next(ln for ln in out.splitlines() if ln.startswith("record"))
    assert "RSN1086, Northridge-01, Sylmar - Olive View Med FF, 360" in line
    assert f"scaled by {factor:.6g} to Sa(T1 = 0.9 s, 5 %) = 0.5 g (was {gm.psa(0.9):.4g} g)" in line
    assert "lasts until t = 2.99 s, the run ends at 1 s" in err
    res = nvib.load_result(tmp_path / "r.npz")
    want = nvib.solve(nvib.load_scene("building_inelastic", ground_motion=scaled), nvib.Newmark(), dt=0.002,
                      t_end=1.0)
    np.testing.assert_allclose(res.u, want.u, rtol=0, atol=1e-12 * np.max(np.abs(want.u)))

    code, out, err = run_cli(capsys, "run", "isolated", "--record", path, "--scale", "2", "--t-end", "0.2")
    assert code == 0, err
    assert f"scaled by 2: PGA {2 * gm.pga:.4g} g" in out
    assert run_cli(capsys, "run", "building", "--record", path, "--sa", "1", "0.2", "--sa-damping", "0.02",
                   "--t-end", "0.1")[0] == 0

    one = write(tmp_path / "one.txt", "\n".join(repr(float(x)) for x in gm.a * 9.80665))
    code, out, err = run_cli(capsys, "run", "building", "--record", one, "--record-dt", "0.01", "--record-units",
                             "m/s^2", "--t-end", "0.1")
    assert code == 0 and "PGA" in out and "m/s^2" in out


@pytest.mark.parametrize("argv, argument, needle", [
    (["pendulum", "--record", "{rec}"], "--record", "scene 'pendulum' has no ground motion to replace"),
    (["building", "--record", "{rec}", "--scale", "2", "--sa", "1", "0.3"], "--sa", "not allowed with argument --scale"),
    (["building", "--scale", "2"], "--scale", "give --record FILE too"),
    (["building", "--record", "{bad}"], "--record", "bad.AT2, line 6: 'x.1E-02' is not a number"),
    (["building", "--record", "{missing}"], "--record", "no such file"),
    (["building", "--record", "{one}", "--record-dt", "0.01"], "--record-units", "is not known"),
    (["building", "--record", "{one}"], "--record-dt", "give their time step"),
    (["building", "--record", "{rec}", "--sa", "1", "0"], "--sa", "must be > 0"),
    (["building", "--record", "{rec}", "--sa", "1", "nan"], "--sa", "must be finite"),
    (["building", "--record", "{rec}", "--sa", "1", "0.3", "--sa-damping", "1.5"], "--sa-damping", "expected 0 <="),
    (["building", "--record", "{zero}", "--sa", "1", "0.3"], "--sa", "PSa at T = 1 s is 0"),
])
def test_run_record_bad_input(tmp_path, argv, argument, needle):
    """Bad input exits 2 with one line naming the option, no traceback."""
    from _cli import nvib_subprocess
    from test_cli_bad_input import assert_bad_input

    header = ["PEER NGA STRONG MOTION DATABASE RECORD", "Northridge-01, 1/17/1994, Sylmar, 360",
              "ACCELERATION TIME SERIES IN UNITS OF G", "NPTS=  7, DT=   .0100 SEC,"]
    bad = peer_written(NORTHRIDGE)
    bad[1] = bad[1][:15] + "  x.1E-02"
    files = {"rec": northridge_like(tmp_path), "bad": write_bytes(tmp_path / "bad.AT2", header + bad, "\r\r\n"),
             "missing": str(tmp_path / "missing.AT2"), "one": write(tmp_path / "one.txt", "0\n0.1\n-0.1\n"),
             "zero": write_bytes(tmp_path / "zero.AT2", header + peer_written([0.0] * 7), "\n")}
    p = nvib_subprocess("run", *[a.format(**files) for a in argv], "--t-end", "0.1", timeout=60)
    last = assert_bad_input(p, "run", argument)
    assert needle in last, last
