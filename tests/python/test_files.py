"""Files say what they hold: a result saved and read back keeps what absolute_a adds to a (the ground's
acceleration); a file written before it was saved refuses absolute_a instead of returning a. A CSV header
is quoted where a name needs it, so any DOF name reads back. A failed run reads back with its failure
whole: status, message, time, step, DOF and Newton's residuals. A file nvib did not write, or a damaged
one, is refused with one ArgumentError naming the file and what is wrong; pickles are never loaded."""

import csv
import io
import os
import pickle

import numpy as np
import pytest

import nvib

FORMATS = (".npz", ".nc")


def _format(ext):
    """The extension, after skipping a .nc test when xarray (the optional extra) is absent."""
    if ext == ".nc":
        pytest.importorskip("xarray")
    return ext


def _without(path, key):
    """Rewrite the file at ``path`` without ``key``, as files were written before ``key`` was saved."""
    if path.suffix == ".npz":
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files if k != key}
        with open(path, "wb") as fh:
            np.savez_compressed(fh, **data)
    else:
        import xarray as xr

        with xr.open_dataset(path) as ds:
            ds = ds.drop_vars(key).load()
        ds.to_netcdf(path)


@pytest.fixture(scope="module")
def building():
    """The building scene under its ground acceleration a_g = 10 sin(pi t) on every floor."""
    return nvib.solve(nvib.load_scene("building"), nvib.Newmark(), dt=0.01, t_end=1.0)


@pytest.mark.parametrize("ext", FORMATS)
def test_absolute_a_survives_a_file(building, ext, tmp_path):
    path = tmp_path / f"b{_format(ext)}"
    assert building.relative_to_ground
    ground = 10.0 * np.sin(np.pi * building.t)
    np.testing.assert_allclose(building.absolute_a - building.a, np.outer(ground, np.ones(6)), rtol=0, atol=1e-14)
    building.save(path)
    back = nvib.load_result(path)
    assert back.relative_to_ground
    np.testing.assert_array_equal(back.a, building.a)
    np.testing.assert_allclose(back.absolute_a, building.absolute_a, rtol=0, atol=1e-15)
    assert np.max(np.abs(back.absolute_a - back.a)) == pytest.approx(10.0, rel=1e-3)  # not a itself
    np.testing.assert_allclose(pickle.loads(pickle.dumps(back)).absolute_a, building.absolute_a, rtol=0, atol=1e-15)


@pytest.mark.parametrize("ext", FORMATS)
def test_ground_on_some_dofs_and_no_ground_survive_a_file(ext, tmp_path):
    """The ground acting on one DOF (a measure), saved in another order: each DOF keeps its own share;
    a model without ground motion reads back with absolute_a = a."""
    gm = nvib.GroundMotion.from_array([0.0, 1.0, -2.0, 0.5, 0.0], dt=0.01, scale=9.80665)
    one = nvib.Model([2.0, 3.0], effects=[{"type": "ground_acceleration", "measure": {1: 1.0}, "signal": gm}])
    res = nvib.solve(one, nvib.CEMDTS(), dt=0.004, t_end=0.04, dofs=[1, 0])
    res.save(tmp_path / f"one{_format(ext)}")
    back = nvib.load_result(tmp_path / f"one{ext}")
    np.testing.assert_allclose(back.absolute_a, res.absolute_a, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(back.absolute_a[:, 1], back.a[:, 1])  # the ground does not act on DOF 0
    assert np.max(np.abs(back.absolute_a[:, 0] - back.a[:, 0])) > 1.0
    free = nvib.solve(nvib.load_scene("hardening"), nvib.CentralDifference(), dt=1e-3, t_end=0.01)
    free.save(tmp_path / f"free{ext}")
    back = nvib.load_result(tmp_path / f"free{ext}")
    assert not back.relative_to_ground
    np.testing.assert_array_equal(back.absolute_a, free.a)


@pytest.mark.parametrize("ext", FORMATS)
def test_a_file_without_the_ground_refuses_absolute_a(building, ext, tmp_path):
    """A file written before the ground's acceleration was saved still reads (u, v, a relative to the
    ground), but absolute_a says what the file lacks instead of returning a."""
    path = tmp_path / f"old{_format(ext)}"
    building.save(path)
    _without(path, "ground_a")
    back = nvib.load_result(path)
    assert back.relative_to_ground
    np.testing.assert_array_equal(back.a, building.a)
    with pytest.raises(nvib.ArgumentError, match=r"ground_a") as exc:
        back.absolute_a
    assert str(path) in str(exc.value) and "relative to the ground" in str(exc.value)
    with pytest.raises(nvib.ArgumentError, match=r"ground_a"):
        pickle.loads(pickle.dumps(back)).absolute_a


ODD_NAMES = ["a,b", 'say "x"', "two\nlines", "cr\rhere", "plain"]


def test_csv_quotes_names_so_they_read_back(tmp_path):
    """DOF and effect names with a comma, double quote or line break are quoted (RFC 4180): csv and
    pandas read the same names and the same numbers back."""
    model = nvib.Model([1.0] * 5, dofs=ODD_NAMES, u0=[0.1, 0.0, 0.0, 0.0, 0.2],
                       effects=[{"type": "spring", "name": 'k,"1"', "measure": {0: 1.0, 4: -1.0}, "k": 4.0}])
    res = nvib.solve(model, nvib.CEMDTS(), dt=0.1, t_end=0.3, record=['k,"1"'])
    path = tmp_path / "odd.csv"
    res.save(path)
    head = ["t"] + [f"{q}:{d}" for q in ("u", "v", "a") for d in ODD_NAMES]
    head += [f'effect:k,"1":{field}' for field in ("measure", "rate", "force")]
    with open(path, encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == head
    table = np.array(rows[1:], dtype=float)
    assert table.shape == (len(res.t), len(head))
    np.testing.assert_array_equal(table[:, 0], res.t)
    np.testing.assert_array_equal(table[:, 1:6], res.u)
    np.testing.assert_array_equal(table[:, 11:16], res.a)
    np.testing.assert_array_equal(table[:, -1], res.effects['k,"1"'].force)

    pd = pytest.importorskip("pandas")
    df = pd.read_csv(path, dtype=str)  # the decimals as written, parsed by Python's float below
    assert list(df.columns) == head
    np.testing.assert_array_equal(np.asarray(df["v:two\nlines"], dtype=float), res.v[:, 2])
    np.testing.assert_array_equal(np.asarray(df["u:cr\rhere"], dtype=float), res.u[:, 3])
    np.testing.assert_array_equal(np.asarray(df['effect:k,"1":measure'], dtype=float), res.u[:, 0] - res.u[:, 4])


def test_csv_of_plain_names_is_unquoted(tmp_path):
    res = nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=1e-3, t_end=0.002)
    res.save(tmp_path / "b.csv")
    lines = (tmp_path / "b.csv").read_text(encoding="utf-8").split("\n")
    assert lines[0] == ",".join(["t"] + [f"{q}:x{k}" for q in "uva" for k in range(1, 7)]) and '"' not in lines[1]
    assert lines[-1] == "" and len(lines) == 2 + len(res.t)  # one line per row, ended by \n


def _failure(f):
    return (f.status, f.message, f.t, f.step, f.dof, list(f.residuals))


def _hardening_newton_fails():
    """One Newton iteration with tolerances no step meets: fails at step 1 with two residuals."""
    model = nvib.Model([1.0], effects=[{"type": "hardening_spring", "measure": {"x": 1.0}, "k0": 100.0, "a": 30.0}],
                       dofs=["x"], u0=[1.5])
    return nvib.solve(model, nvib.Newmark(newton=nvib.Newton(iteration="newton", max_iter=1, rtol=1e-15, atol=1e-15)),
                      dt=0.01, t_end=0.1, throw=False)


@pytest.mark.parametrize("ext", FORMATS)
def test_a_failed_run_keeps_its_failure(ext, tmp_path):
    diverged = nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=0.05, t_end=5.0, throw=False)
    newton = _hardening_newton_fails()
    assert _failure(diverged.failure)[:5] == (nvib.Status.diverged, diverged.failure.message, 0.45, 9, 0)
    assert newton.failure.status == nvib.Status.newton_failed and len(newton.failure.residuals) == 2
    for name, res in (("diverged", diverged), ("newton", newton)):
        path = tmp_path / f"{name}{_format(ext)}"
        res.save(path)
        back = nvib.load_result(path)
        assert back.status == res.status and not back.success
        assert _failure(back.failure) == _failure(res.failure)
        np.testing.assert_array_equal(back.u, res.u)
    ok = tmp_path / f"ok{ext}"
    nvib.solve(nvib.load_scene("hardening"), nvib.CentralDifference(), dt=1e-3, t_end=0.01).save(ok)
    assert nvib.load_result(ok).failure is None


def _npz_with(good, path, **changes):
    with np.load(good, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data.update(changes)
    np.savez(path, **data)


def _half(good, path):
    data = good.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _flipped(good, path):
    """The file with one byte in the middle of its u changed, as a bad disk or transfer leaves it (a byte
    of the archive's own headers, such as a member's date, can change unseen)."""
    import zipfile

    data = bytearray(good.read_bytes())
    with zipfile.ZipFile(good) as z:
        member = z.getinfo("u.npy")
    off = member.header_offset  # the local header: 30 bytes, the name, the extra field, then the data
    start = off + 30 + int.from_bytes(data[off + 26:off + 28], "little") + int.from_bytes(data[off + 28:off + 30], "little")
    data[start + member.compress_size // 2] ^= 0xFF
    path.write_bytes(bytes(data))


def _npy_bytes():
    buf = io.BytesIO()
    np.save(buf, np.arange(3.0))
    return buf.getvalue()


# name: (how to write it from a good .npz / .nc and the scratch path, what the message says)
BAD_FILES = {
    "empty.npz": (lambda good, p: p.write_bytes(b""), r"is empty \(0 bytes\)"),
    "text.npz": (lambda good, p: p.write_text("t,u:x\n0.0,1.0\n", encoding="utf-8"),
                 r"is not a \.npz archive \(a zip file\) but text"),
    "other.npz": (lambda good, p: np.savez(p, x=np.arange(3), y=np.ones(2)),
                  r"is not a result nvib saved: it has no t, u, v, a, dofs \(it holds x, y\)"),
    "truncated.npz": (_half, r"is damaged or truncated"),
    "damaged.npz": (_flipped, r"is damaged or truncated"),
    "objects.npz": (lambda good, p: np.savez(p, t=np.array([{"t": 0.0}], dtype=object)),
                    r"holds Python objects in t, which nvib never saves and does not read"),
    "array.npz": (lambda good, p: p.write_bytes(_npy_bytes()), r"but a NumPy \.npy array"),
    "pickle.npz": (lambda good, p: p.write_bytes(pickle.dumps({"t": [0.0]})),
                   r"but a Python pickle, which nvib does not load"),
    "netcdf.npz": (lambda good, p: p.write_bytes(b"CDF\x01" + bytes(60)),
                   r"but a netCDF-3 file: .* would end in \.nc"),
    "shape.npz": (lambda good, p: _npz_with(good, p, u=np.zeros((3, 2))),
                  r"its u is an array of shape \(3, 2\) and dtype float64, not 11 x 6 numbers"),
    "strings.npz": (lambda good, p: _npz_with(good, p, t=np.array(["0"] * 11)), r"its t is an array of shape \(11,\)"),
    "status.npz": (lambda good, p: _npz_with(good, p, status=np.array("fine")),
                   r"its status 'fine' is none of success"),
    "empty.nc": (lambda good, p: p.write_bytes(b""), r"is empty \(0 bytes\)"),
    "text.nc": (lambda good, p: p.write_text("netcdf?\n", encoding="utf-8"),
                r"is not a netCDF file but text"),
    "zip.nc": (lambda good, p: p.write_bytes(good.with_suffix(".npz").read_bytes()),
               r"is not a netCDF file but a zip archive: .* would end in \.npz"),
    "other.nc": (lambda good, p: __import__("xarray").Dataset({"x": ("n", [1.0, 2.0])}).to_netcdf(p),
                 r"is not a result nvib saved: it has no u, v, a, time, dof \(it holds x\)"),
    "truncated.nc": (_half, r"cannot be read as netCDF: it is damaged or truncated"),
}


@pytest.fixture(scope="module")
def good_files(tmp_path_factory):
    """A result saved as .npz (and .nc when xarray is there): 11 saved times of the building's 6 DOFs."""
    folder = tmp_path_factory.mktemp("good")
    res = nvib.solve(nvib.load_scene("building"), nvib.Newmark(), dt=0.1, t_end=1.0)
    res.save(folder / "good.npz")
    try:
        res.save(folder / "good.nc")
    except ImportError:
        pass
    return folder


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_a_file_nvib_did_not_write_is_refused_by_name(name, good_files, tmp_path):
    write, says = BAD_FILES[name]
    good = good_files / f"good{os.path.splitext(name)[1]}"
    if name in ("other.nc", "truncated.nc"):  # written by xarray
        pytest.importorskip("xarray")
    path = tmp_path / name
    write(good, path)
    with pytest.raises(nvib.ArgumentError, match=says) as exc:
        nvib.load_result(path)
    assert isinstance(exc.value, ValueError) and exc.value.argument == "path"
    assert str(exc.value).startswith(f"path: {str(path)!r} ")
    assert "allow_pickle" not in str(exc.value) and "unsafe" not in str(exc.value)


def test_a_missing_file_says_so(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.npz"):
        nvib.load_result(tmp_path / "nowhere.npz")
