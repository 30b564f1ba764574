"""Results as tables and files: pandas and xarray views hold the same numbers and the run's
description; save/load round trips are exact; CSV holds shortest round-trip decimals; a missing
extra says which to install."""

import builtins

import numpy as np
import pytest

import nvib


@pytest.fixture(scope="module")
def result():
    return nvib.solve(nvib.load_scene("building"), nvib.Newmark(), dt=0.1, t_end=1.0, energy=True, dofs=["x2", "x6"])


def test_to_pandas(result):
    pd = pytest.importorskip("pandas")
    df = result.to_pandas()
    assert isinstance(df, pd.DataFrame) and df.index.name == "t"
    assert list(df.columns[:3]) == ["u:x2", "u:x6", "v:x2"] and "energy:balance_error" in df.columns
    np.testing.assert_array_equal(df.index.values, result.t)
    np.testing.assert_array_equal(df["a:x6"].values, result.a[:, 1])
    assert df.attrs["scheme"] == repr(result.scheme) and df.attrs["status"] == "success" and df.attrs["dt"] == 0.1
    assert df.attrs["stats_num_steps"] == 10


def test_to_xarray_and_netcdf_round_trip(result, tmp_path):
    pytest.importorskip("xarray")
    ds = result.to_xarray()
    assert ds["u"].dims == ("time", "dof") and list(ds["dof"].values) == ["x2", "x6"]
    np.testing.assert_array_equal(ds["v"].values, result.v)
    path = tmp_path / "run.nc"
    result.save(path)
    back = nvib.load_result(path)
    for key in ("t", "u", "v", "a"):
        np.testing.assert_array_equal(getattr(back, key), getattr(result, key))
    assert back.dofs == result.dofs and back.status == result.status and back.stats.num_steps == 10


def test_npz_round_trip_keeps_everything(result, tmp_path):
    path = tmp_path / "run.npz"
    result.save(path)
    back = nvib.load_result(path)
    for key in ("t", "u", "v", "a"):
        np.testing.assert_array_equal(getattr(back, key), getattr(result, key))
    np.testing.assert_array_equal(back.energy.balance_error, result.energy.balance_error)
    assert back.stats.as_dict() == result.stats.as_dict()
    assert back.scheme == repr(result.scheme) and back.dt == result.dt and back.dofs == ["x2", "x6"]
    failed = nvib.solve(nvib.load_scene("building"), nvib.CentralDifference(), dt=0.05, t_end=5.0, throw=False)
    failed.save(tmp_path / "failed.npz")
    back = nvib.load_result(tmp_path / "failed.npz")
    assert back.status == nvib.Status.diverged and back.failure.message == failed.failure.message
    np.testing.assert_array_equal(back.u, failed.u)
    with pytest.raises(nvib.ArgumentError) as exc:
        nvib.load_result(tmp_path / "run.txt")
    assert exc.value.argument == "path"


def test_csv_has_shortest_decimals(tmp_path):
    res = nvib.solve(nvib.Model([1.0], u0=[0.3], effects=[{"type": "spring", "measure": {0: 1.0}, "k": 4.0}]),
                     nvib.CEMDTS(), dt=0.1, t_end=0.3)
    path = tmp_path / "run.csv"
    res.save(path)
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "t,u:u0,v:u0,a:u0"
    assert lines[4].split(",")[0] == "0.30000000000000004" and lines[1].split(",")[1] == "0.3"  # t = 3 * 0.1 in floats
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 1], res.u[:, 0])  # read back exactly


def test_missing_extra_names_it(result, monkeypatch):
    real_import = builtins.__import__

    def no_pandas(name, *args, **kw):
        if name == "pandas" or name.startswith("pandas."):
            raise ImportError("no pandas here")
        return real_import(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", no_pandas)
    monkeypatch.delitem(__import__("sys").modules, "pandas", raising=False)
    with pytest.raises(ImportError, match=r'pip install "nvib\[pandas\]"'):
        result.to_pandas()


def test_cli_out_writes_netcdf(tmp_path):
    """nvib run --out FILE.nc writes netCDF through Result.save (or says which extra it needs)."""
    import importlib.util
    import subprocess
    import sys

    out = tmp_path / "b.nc"
    p = subprocess.run([sys.executable, "-m", "nvib", "run", "building", "--t-end", "0.5", "--out", str(out)],
                       capture_output=True, text=True)
    if importlib.util.find_spec("xarray") is None:
        assert p.returncode == 2 and 'pip install "nvib[xarray]"' in p.stderr and not out.exists()
        return
    assert p.returncode == 0, p.stderr
    back = nvib.load_result(out)
    assert back.t[-1] == pytest.approx(0.5005) and back.dofs == [f"x{k}" for k in range(1, 7)]
    assert back.units == ["m"] * 6 and back.relative_to_ground
