"""check_law: a Python law's declared slopes against finite differences of its own force. Right slopes
pass to the differences' accuracy; a wrong slope planted in a law (smooth, with velocity, with memory) is
found, at the point where theory puts its largest error and with that error; kinks are judged against
the closer one-sided difference; bad input names the argument."""

import numpy as np
import pytest

import nvib

K, A, C = 1e6, 1e9, 50.0  # a hardening spring k d + a d^3 beside a damper c d'


def spring(d, dd, t):
    return K * d + A * d ** 3 + C * dd


def spring_slopes(d, dd, t):
    return K + 3 * A * d * d, C


PATH = np.linspace(-0.02, 0.02, 81)
RATE = np.cos(100 * PATH)


def test_right_slopes_pass():
    check = nvib.check_law({"type": "callable", "law": spring, "tangent": spring_slopes}, PATH, rate=RATE)
    # central differences of a cubic: truncation h^2 a (1e-16 relative) and round-off eps f / h (~1e-9)
    assert check.ok and check.worst[4] < 1e-6 and not check.kink.any()
    np.testing.assert_allclose(check.fd_d, K + 3 * A * PATH ** 2, rtol=1e-6)
    assert "slopes agree" in str(check)


def test_a_wrong_stiffness_is_found_where_it_is_largest():
    """Declared k + 2 a d^2 for k + 3 a d^2: the relative error a d^2 / (k + 3 a d^2) grows with |d|, so the
    worst point is an end of the path, with that error (0.18 at |d| = 0.02)."""
    wrong = {"type": "callable", "law": spring, "tangent": lambda d, dd, t: (K + 2 * A * d * d, C)}
    check = nvib.check_law(wrong, PATH, rate=RATE)
    k, which, declared, fd, err = check.worst
    assert not check.ok and which == "df/dd" and abs(PATH[k]) == 0.02
    assert err == pytest.approx(A * 0.02 ** 2 / (K + 3 * A * 0.02 ** 2), rel=1e-6)
    assert declared == K + 2 * A * 0.02 ** 2 and fd == pytest.approx(K + 3 * A * 0.02 ** 2, rel=1e-8)
    assert "WRONG SLOPE" in str(check) and f"point {k}" in str(check)


def test_a_wrong_damping_slope_is_found():
    """A quadratic damper c d' |d'| declared with slope c |d'| (half of 2 c |d'|): error 0.5 wherever d' != 0."""
    law = {"type": "callable", "law": lambda d, dd, t: C * dd * abs(dd),
           "tangent": lambda d, dd, t: (0.0, C * abs(dd))}
    check = nvib.check_law(law, PATH, rate=RATE)
    assert not check.ok and check.worst[1] == "df/dd'" and check.worst[4] == pytest.approx(0.5, rel=1e-6)


FY = 10.0


def elastoplastic(d, dd, t, state):
    """An elastic-perfectly plastic spring (stiffness 1000, strength FY) with its plastic deformation as state."""
    dp, = state
    f = 1000.0 * (d - dp)
    if abs(f) > FY:
        f = np.sign(f) * FY
        dp = d - f / 1000.0
    return f, (dp,)


def elastoplastic_slopes(d, dd, t, state):
    return (0.0 if abs(1000.0 * (d - state[0])) > FY else 1000.0), 0.0


def test_a_law_with_memory_is_checked_from_the_state_the_path_commits():
    path = 0.03 * np.sin(np.linspace(0, 4 * np.pi, 200))  # two cycles to 3x the yield deformation
    effect = {"type": "callable", "law": elastoplastic, "tangent": elastoplastic_slopes, "state": [0.0],
              "uses_velocity": False}
    check = nvib.check_law(effect, path)
    assert check.ok and check.worst[4] < 1e-6
    plastic = check.slope_d == 0.0
    assert 40 < plastic.sum() < 160  # the path yields in both directions and unloads elastically
    # the elastic tangent declared everywhere: wrong where the law flows (difference 0, declared 1000)
    wrong = nvib.check_law(dict(effect, tangent=lambda d, dd, t, s: (1000.0, 0.0)), path)
    k, which, declared, fd, err = wrong.worst
    assert not wrong.ok and err == 1.0 and declared == 1000.0 and fd == 0.0 and plastic[k]


def test_a_kink_is_judged_against_the_closer_one_sided_difference():
    """A bilinear elastic spring whose path lands on its corner: at d = 0.01 either slope is right, and the
    point is marked a kink; a slope that is neither is still wrong there."""
    law = lambda d, dd, t: 1000.0 * d if d <= 0.01 else 10.0 + 50.0 * (d - 0.01)  # noqa: E731
    slopes = lambda d, dd, t: (1000.0 if d <= 0.01 else 50.0, 0.0)  # noqa: E731
    path = np.array([0.0, 0.005, 0.01, 0.015])
    check = nvib.check_law({"type": "callable", "law": law, "tangent": slopes, "uses_velocity": False}, path)
    assert check.ok and list(check.kink) == [False, False, True, False] and check.fd_d[2] == pytest.approx(1000.0)
    neither = nvib.check_law({"type": "callable", "law": law, "tangent": lambda d, dd, t: (500.0, 0.0),
                              "uses_velocity": False}, path)
    assert not neither.ok and neither.error_d[2] == pytest.approx(0.5, rel=1e-6)


@pytest.mark.parametrize("effect, d, arg", [
    ({"type": "bilinear", "k": 1.0, "fy": 1.0}, [0.0], "effect.type"),
    ({"type": "callable", "law": spring}, [0.0], "effect.tangent"),
    ({"type": "callable", "law": 3.0, "tangent": spring_slopes}, [0.0], "effect.law"),
    ({"type": "callable", "law": spring, "tangent": spring_slopes, "measure": {0: 1.0}}, [0.0], "effect.measure"),
    ({"type": "callable", "law": spring, "tangent": spring_slopes}, [], "d"),
])
def test_bad_input_names_the_argument(effect, d, arg):
    with pytest.raises((nvib.ArgumentError, nvib.ArgumentTypeError)) as exc:
        nvib.check_law(effect, d)
    assert exc.value.argument == arg


def test_a_compiled_law_is_checked_through_its_pointer():
    """The same check for a compiled law (here a ctypes pointer of nvib.LAW_SIGNATURE: no compiler needed):
    its declared out[1] against differences of its out[0], from the state the path commits."""
    from _compiled_laws import BILINEAR, HARDENING

    path = 0.03 * np.sin(np.linspace(0, 4 * np.pi, 200))
    # k0 (1 + a d^2) d with k0 = K, a = A / K: the spring K d + A d^3 of the tests above
    good = nvib.check_law({"type": "compiled", "law": HARDENING, "params": [K, A / K], "uses_time": False}, PATH)
    assert good.ok and good.worst[4] < 1e-6
    memory = nvib.check_law({"type": "compiled", "law": BILINEAR, "params": [1000.0, 10.0, 0.05],
                             "state": [0.0, 0.0, 0.0]}, path)
    assert memory.ok and np.any(memory.slope_d < 1000.0)  # it yields: the slope b k there, found right
    # a wrong slope planted: the bilinear law's arithmetic with its elastic slope everywhere
    from nvib._compiled import ctypes_law
    from _compiled_laws import bilinear_py

    def elastic_slope(p, s, d, dd, t, out, trial):
        code = bilinear_py(p, s, d, dd, t, out, trial)
        out[1] = p[0]
        return code

    wrong = nvib.check_law({"type": "compiled", "law": ctypes_law(elastic_slope), "params": [1000.0, 10.0, 0.05],
                            "state": [0.0, 0.0, 0.0]}, path)
    k, which, declared, fd, err = wrong.worst
    assert not wrong.ok and declared == 1000.0 and fd == pytest.approx(50.0, rel=1e-6)
