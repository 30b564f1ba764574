"""Generate nvib's synthetic ground-motion record SGM-1: python/nvib/scenes/records/sgm1.AT2.

The record is made here, from a fixed seed, so that nvib can ship a strong motion whose
redistribution is not in question (it is the project's own, MIT like the project). Method:

1. Gaussian white noise (numpy.random.default_rng(SEED), unit variance, held constant over each
   0.01-s step) through the Kanai-Tajimi ground filter (Kanai 1957; Tajimi 1960) and the
   Clough-Penzien high-pass filter (Clough & Penzien 1975): the stationary acceleration has the
   power spectral density

       S(w) = S0 (wg^4 + 4 zg^2 wg^2 w^2) / ((wg^2 - w^2)^2 + 4 zg^2 wg^2 w^2)
                 * w^4 / ((wf^2 - w^2)^2 + 4 zf^2 wf^2 w^2)

   with firm-soil values wg = 15.6 rad/s, zg = 0.6 (the firm-soil values usually attributed to
   Kanai in the random-vibration literature) and wf = 1.6 rad/s, zf = 0.6 (a high-pass corner a
   tenth of wg, the usual choice; Der Kiureghian & Neuenhofer 1992 use 15, 0.6, 1.5, 0.6 for firm
   soil). The two
   filters form one linear system of four states, integrated exactly for the piecewise-constant
   input (zero-order-hold discretisation, scipy.linalg.expm): no time-stepping error.
2. Amplitude modulation by the envelope of Jennings, Housner & Tsai (1968): (t/t1)^2 up to t1,
   1 up to t2, exp(-c (t - t2)) after, with t1 = 2 s, t2 = 12 s, c = 0.3 1/s over 30 s (our
   choice): a strong phase of about 10 s, of the order of a magnitude-7 event's at moderate
   distance. The envelope is 0 at
   t = 0, so the record starts at rest with a(0) = 0, and has fallen to 0.5 % at t = 30 s.
3. Baseline correction: the ground velocity and displacement at the end of the modulated noise are
   not zero (the noise drifts). A correction c(t) = tau (1 - tau) p(tau), tau = t / T, p a cubic,
   is subtracted from the acceleration: it vanishes at both ends (so a(0) = 0 and the end value are
   kept), its coefficients minimise the mean square ground displacement (least squares on the
   integrated displacement, the classic polynomial baseline fit) subject to zero velocity and
   displacement at t = T. Velocity and displacement are integrated exactly for an acceleration
   linear between samples, as nvib reads a record.
4. Scaling to a peak ground acceleration of 0.40 g.
5. Output in the PEER NGA-West2 AT2 format: four header lines, then the values in g, five a line.

The measures printed are PGA, PGV, PGD, the Arias intensity I_A = pi / (2 g) int a^2 dt (Arias
1970), the significant duration D5-95 between 5 % and 95 % of I_A (Trifunac & Brady 1975) and the
5 %-damped pseudo-acceleration spectrum PSa = w^2 max|u| of the linear SDOF, solved exactly for the
piecewise-linear record (Nigam & Jennings 1969).

References
    Arias, A. (1970). A measure of earthquake intensity. In R. J. Hansen (ed.), Seismic Design for
        Nuclear Power Plants, MIT Press, 438-483.
    Clough, R. W., Penzien, J. (1975). Dynamics of Structures. McGraw-Hill, New York.
    Der Kiureghian, A., Neuenhofer, A. (1992). Response spectrum method for multi-support seismic
        excitations. Earthquake Engineering & Structural Dynamics 21(8), 713-740.
    Jennings, P. C., Housner, G. W., Tsai, N. C. (1968). Simulated earthquake motions. Earthquake
        Engineering Research Laboratory, California Institute of Technology, Pasadena.
    Kanai, K. (1957). Semi-empirical formula for the seismic characteristics of the ground.
        Bulletin of the Earthquake Research Institute, University of Tokyo 35, 309-325.
    Nigam, N. C., Jennings, P. C. (1969). Calculation of response spectra from strong-motion
        earthquake records. Bulletin of the Seismological Society of America 59(2), 909-922.
    Tajimi, H. (1960). A statistical method of determining the maximum response of a building
        structure during an earthquake. Proc. 2nd World Conference on Earthquake Engineering,
        Tokyo, vol. 2, 781-797.
    Trifunac, M. D., Brady, A. G. (1975). A study on the duration of strong earthquake ground
        motion. Bulletin of the Seismological Society of America 65(3), 581-626.

Usage (from the repository root; NumPy and SciPy, matplotlib for --plot only):

    python tools/make_ground_motion.py                # write the record, print its measures
    python tools/make_ground_motion.py --check        # exit 1 unless the file is what this generates
    python tools/make_ground_motion.py --plot sgm1.png
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np
from scipy.linalg import expm

G = 9.80665  # standard gravity [m/s^2]: the record is in g

SEED = 20260101
DT = 0.01  # [s]
DURATION = 30.0  # [s]
NPTS = int(round(DURATION / DT)) + 1  # samples at 0, DT, ..., DURATION
PGA = 0.40  # [g]

# Kanai-Tajimi ground filter and Clough-Penzien high-pass filter, firm soil
OMEGA_G, ZETA_G = 15.6, 0.6  # [rad/s], [-]
OMEGA_F, ZETA_F = 1.6, 0.6  # [rad/s], [-]

# Jennings, Housner & Tsai (1968) envelope
T1, T2, DECAY = 2.0, 12.0, 0.3  # [s], [s], [1/s]

BASELINE_ORDER = 3  # degree of p in the correction tau (1 - tau) p(tau)

SPECTRUM_PERIODS = (0.1, 0.2, 0.5, 0.8, 1.0, 2.0)  # [s]
SPECTRUM_DAMPING = 0.05

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUTPUT = os.path.join(ROOT, "python", "nvib", "scenes", "records", "sgm1.AT2")

TITLE = f"nvib synthetic ground motion SGM-1, generated by tools/make_ground_motion.py with seed {SEED}"
EVENT = ("Kanai-Tajimi (1957/1960) + Clough-Penzien (1975) filtered white noise, "
         "Jennings et al. (1968) envelope")
VALUES_PER_LINE = 5


# ---- generation ---------------------------------------------------------------------------------

def filter_system(omega_g=OMEGA_G, zeta_g=ZETA_G, omega_f=OMEGA_F, zeta_f=ZETA_F):
    """(A, B, C) of the Kanai-Tajimi and Clough-Penzien filters in series: x' = A x + B w, a = C x.

    Kanai-Tajimi: the ground layer x1'' + 2 zg wg x1' + wg^2 x1 = -w, whose absolute acceleration
    a1 = x1'' + w = -(2 zg wg x1' + wg^2 x1) is the filtered motion. Clough-Penzien: an oscillator
    x2'' + 2 zf wf x2' + wf^2 x2 = -a1 whose relative acceleration a = x2'' is a1 with the low
    frequencies taken out (|H| ~ w^2 below wf), so that the ground velocity and displacement of the
    stationary process stay bounded. a has no direct term in w (the combined filter is strictly
    proper), so it is C x."""
    kt = np.array([2.0 * zeta_g * omega_g, omega_g ** 2])  # a1 = -(kt[0] x1' + kt[1] x1)
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[1] = [-omega_g ** 2, -2.0 * zeta_g * omega_g, 0.0, 0.0]
    A[2, 3] = 1.0
    A[3] = [kt[1], kt[0], -omega_f ** 2, -2.0 * zeta_f * omega_f]  # x2'' = -a1 - 2 zf wf x2' - wf^2 x2
    B = np.array([0.0, -1.0, 0.0, 0.0])
    C = A[3].copy()  # a = x2''
    return A, B, C


def filtered_noise(n, dt, rng):
    """n samples (from rest, so the first is 0) of the filtered white noise: exact for the noise
    held constant over each step (zero-order hold), x_{k+1} = Phi x_k + Gamma w_k."""
    A, B, C = filter_system()
    # expm of [[A, B], [0, 0]] h gives Phi and Gamma = int_0^h e^{A s} ds B in one go
    M = np.zeros((5, 5))
    M[:4, :4] = A
    M[:4, 4] = B
    E = expm(M * dt)
    phi, gamma = E[:4, :4], E[:4, 4]
    w = rng.standard_normal(n)
    x = np.zeros(4)
    a = np.empty(n)
    for k in range(n):
        a[k] = C @ x
        x = phi @ x + gamma * w[k]
    return a


def envelope(t, t1=T1, t2=T2, c=DECAY):
    """Jennings, Housner & Tsai (1968): (t/t1)^2, then 1, then exp(-c (t - t2))."""
    t = np.asarray(t, dtype=float)
    return np.where(t < t1, (t / t1) ** 2, np.where(t <= t2, 1.0, np.exp(-c * (t - t2))))


def integrate(a, dt):
    """Velocity and displacement from rest of an acceleration linear between its samples, exactly:
    v_{k+1} = v_k + h (a_k + a_{k+1}) / 2, d_{k+1} = d_k + h v_k + h^2 (2 a_k + a_{k+1}) / 6.
    Works column by column on a 2-D array."""
    a = np.asarray(a, dtype=float)
    dv = 0.5 * dt * (a[:-1] + a[1:])
    v = np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(dv, axis=0)])
    dd = dt * v[:-1] + dt * dt * (2.0 * a[:-1] + a[1:]) / 6.0
    d = np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(dd, axis=0)])
    return v, d


def baseline_correct(a, dt, order=BASELINE_ORDER):
    """a - c with c = tau (1 - tau) sum_j b_j tau^j (tau = t / T): the b_j minimise sum d_k^2 (the
    corrected ground displacement) subject to v(T) = d(T) = 0. Solved as one KKT system; the basis
    is in tau so that the system is well scaled whatever T."""
    n = a.size
    tau = np.arange(n) / (n - 1)
    basis = np.stack([tau * (1.0 - tau) * tau ** j for j in range(order + 1)], axis=1)
    v0, d0 = integrate(a, dt)
    vb, db = integrate(basis, dt)
    # corrected displacement d0 - db b: least squares on it, two equality constraints at the end
    m = order + 1
    K = np.zeros((m + 2, m + 2))
    K[:m, :m] = db.T @ db
    cons = np.stack([vb[-1], db[-1]])  # cons b = [v0(T), d0(T)]
    K[:m, m:] = cons.T
    K[m:, :m] = cons
    rhs = np.concatenate([db.T @ d0, [v0[-1], d0[-1]]])
    b = np.linalg.solve(K, rhs)[:m]
    return a - basis @ b


def generate(seed=SEED):
    """(t, a in g, raw): the record, and the modulated noise before the baseline correction at the
    same scale (to report what the correction removed)."""
    t = DT * np.arange(NPTS)
    rng = np.random.default_rng(seed)
    raw = filtered_noise(NPTS, DT, rng) * envelope(t)
    corrected = baseline_correct(raw, DT)
    scale = PGA / np.max(np.abs(corrected))  # in g; the correction changes the peak, so scale last
    return t, corrected * scale, raw * scale


# ---- the AT2 file ---------------------------------------------------------------------------------

def at2_text(a, dt=DT):
    """PEER NGA-West2 AT2: title, event/method, units, NPTS/DT; then the values in g, 5 a line in
    Fortran E15.7 style."""
    lines = [TITLE, EVENT, "ACCELERATION TIME SERIES IN UNITS OF G",
             f"NPTS={a.size:6d}, DT={f'{dt:.4f}'.lstrip('0'):>8s} SEC"]  # NGA-West2: "DT=   .0100"
    for k in range(0, a.size, VALUES_PER_LINE):
        lines.append("".join(f"{x:15.7E}" for x in a[k:k + VALUES_PER_LINE]))
    return "\n".join(lines) + "\n"


def parse_at2(text):
    """(header lines, values) of the text of an AT2 file as written by at2_text."""
    lines = text.splitlines()
    return lines[:4], np.array([float(f) for line in lines[4:] for f in line.split()])


# ---- measures -----------------------------------------------------------------------------------

def measures(a, dt=DT):
    """PGA [g], PGV [m/s], PGD [m], Arias intensity [m/s], D5-95 [s] (with the 5 % and 95 % times)
    of a record in g, linear between samples."""
    acc = a * G
    v, d = integrate(acc, dt)
    # int a^2 over each interval of a linear a: h (a0^2 + a0 a1 + a1^2) / 3
    e = dt * (acc[:-1] ** 2 + acc[:-1] * acc[1:] + acc[1:] ** 2) / 3.0
    husid = np.concatenate([[0.0], np.cumsum(e)])
    arias = math.pi / (2.0 * G) * husid[-1]
    t = dt * np.arange(a.size)
    t5, t95 = np.interp([0.05 * husid[-1], 0.95 * husid[-1]], husid, t)  # husid increases
    return {"pga": np.max(np.abs(a)), "pgv": np.max(np.abs(v)), "pgd": np.max(np.abs(d)),
            "arias": arias, "t5": t5, "t95": t95, "d5_95": t95 - t5}


def pseudo_spectrum(a, dt, periods, damping=SPECTRUM_DAMPING, tail=3.0, points_per_period=200):
    """PSa = w^2 max|u| [units of a] of u'' + 2 z w u' + w^2 u = -a_g from rest, a_g linear between
    its samples (Nigam & Jennings 1969): exact over each step, the step map being expm of the 4x4
    matrix of the state [u, u', a_g, a_g']. The peak is taken on sub-steps of at most T / 200 (at the
    record's samples alone a short period's peak falls between them: at T = 0.1 s, 10 samples a
    period, up to 5 % low) and over ``tail`` times the longest period of free vibration after the
    record, where a long period's peak may fall."""
    periods = np.asarray(periods, dtype=float)
    nsub = int(math.ceil(dt * points_per_period / periods.min()))
    h = dt / nsub
    ag = np.concatenate([a, np.zeros(int(math.ceil(tail * periods.max() / dt)))])
    slope = np.diff(ag) / dt
    # the record at the sub-steps (exact: it is linear within each interval) and its slope there
    frac = np.arange(nsub) / nsub
    fine = (ag[:-1, None] + slope[:, None] * dt * frac).ravel()
    fine_slope = np.repeat(slope, nsub)
    phi = np.empty((periods.size, 2, 2))
    g0, g1 = np.empty((periods.size, 2)), np.empty((periods.size, 2))
    for i, T in enumerate(periods):
        w = 2.0 * math.pi / T
        M = np.zeros((4, 4))
        M[0, 1] = 1.0
        M[1] = [-w * w, -2.0 * damping * w, -1.0, 0.0]
        M[2, 3] = 1.0
        E = expm(M * h)
        phi[i], g0[i], g1[i] = E[:2, :2], E[:2, 2], E[:2, 3]  # x+ = phi x + g0 a_g + g1 a_g'
    x = np.zeros((periods.size, 2))
    umax = np.zeros(periods.size)
    for k in range(fine.size):  # all periods at once
        x = np.einsum("pij,pj->pi", phi, x) + g0 * fine[k] + g1 * fine_slope[k]
        np.maximum(umax, np.abs(x[:, 0]), out=umax)
    return (2.0 * math.pi / periods) ** 2 * umax


# ---- report and plot ------------------------------------------------------------------------------

def report(a, raw, out=sys.stdout):
    """Print the measures of the record ``a`` [g] and the end state before the baseline correction."""
    m = measures(a)
    sa = pseudo_spectrum(a, DT, SPECTRUM_PERIODS)
    print(f"seed {SEED}: {a.size} samples, dt = {DT} s, a(0) = {a[0]:.3g} g, a(end) = {a[-1]:.3g} g", file=out)
    for label, x in (("before baseline correction", raw), ("after (as written)        ", a)):
        v, d = integrate(x * G, DT)
        print(f"{label}: at t = {DURATION:g} s v = {v[-1] * 100:+.3e} cm/s, d = {d[-1] * 100:+.3e} cm; "
              f"peak |d| {np.max(np.abs(d)) * 100:.1f} cm", file=out)
    print(f"PGA = {m['pga']:.3f} g, PGV = {m['pgv'] * 100:.1f} cm/s, PGD = {m['pgd'] * 100:.1f} cm, "
          f"Arias = {m['arias']:.2f} m/s, D5-95 = {m['d5_95']:.2f} s ({m['t5']:.2f} to {m['t95']:.2f} s)", file=out)
    print("PSa (5 %): " + ", ".join(f"{T:g} s {s:.3f} g" for T, s in zip(SPECTRUM_PERIODS, sa)), file=out)


def plot(a, path):
    """Acceleration, velocity and displacement histories and the 5 % PSa spectrum."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = DT * np.arange(a.size)
    v, d = integrate(a * G, DT)
    periods = np.geomspace(0.05, 5.0, 120)
    sa = pseudo_spectrum(a, DT, periods)
    marks = pseudo_spectrum(a, DT, SPECTRUM_PERIODS)
    m = measures(a)
    fig = plt.figure(figsize=(10, 8), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=[1.6, 1])
    hist = [fig.add_subplot(grid[0, 0])]
    hist += [fig.add_subplot(grid[k, 0], sharex=hist[0]) for k in (1, 2)]
    for ax, y, label in zip(hist, (a, v * 100, d * 100), ("a [g]", "v [cm/s]", "d [cm]")):
        ax.plot(t, y, lw=0.7)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in hist:
        ax.axvspan(m["t5"], m["t95"], color="C1", alpha=0.08)
    hist[0].set_title(f"SGM-1 (seed {SEED}): PGA {m['pga']:.2f} g, PGV {m['pgv'] * 100:.0f} cm/s, "
                      f"PGD {m['pgd'] * 100:.1f} cm, D5-95 {m['d5_95']:.1f} s (shaded)", fontsize=10)
    hist[2].set_xlabel("t [s]")
    ax = fig.add_subplot(grid[:, 1])
    ax.plot(periods, sa, lw=1.2, label="PSa, 5 % damping")
    ax.plot(SPECTRUM_PERIODS, marks, "o", ms=4, color="C3")
    for T, s in zip(SPECTRUM_PERIODS, marks):
        ax.annotate(f"{s:.2f}", (T, s), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.axhline(m["pga"], color="0.5", lw=0.7, ls="--", label="PGA")
    ax.set_xscale("log")
    ax.set_xlabel("T [s]")
    ax.set_ylabel("PSa [g]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ---- main -----------------------------------------------------------------------------------------

def check(path):
    """True if the file at ``path`` holds what generate() makes: the same header lines, and the same
    values to within one unit in the last written digit (1e-7 relative), so that a last-digit
    rounding flip from a different floating-point library does not count as a change."""
    _, a, _ = generate()
    expected_text = at2_text(a)
    if not os.path.exists(path):
        print(f"{path}: missing", file=sys.stderr)
        return False
    with open(path, encoding="ascii") as fh:
        text = fh.read()
    if text == expected_text:
        return True
    expected_header, expected = parse_at2(expected_text)
    header, values = parse_at2(text)
    if header != expected_header:
        print(f"{path}: header differs from the generated one", file=sys.stderr)
        return False
    if values.shape != expected.shape:
        print(f"{path}: {values.size} values, the generator makes {expected.size}", file=sys.stderr)
        return False
    bad = np.flatnonzero(np.abs(values - expected) > 1e-7 * np.abs(expected) + 1e-15)
    if bad.size:
        k = bad[0]
        print(f"{path}: {bad.size} values differ, first sample {k}: {float(values[k])!r} in the file, "
              f"{float(expected[k])!r} generated", file=sys.stderr)
        return False
    return True


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=OUTPUT, help="the AT2 file to write or check (default: %(default)s)")
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 unless the file equals what this script generates")
    parser.add_argument("--plot", metavar="PNG", help="also save a figure of the histories and the spectrum")
    args = parser.parse_args(argv)
    if args.check:
        ok = check(args.out)
        print(f"{args.out}: {'matches the generator' if ok else 'DIFFERS from the generator'}")
        return 0 if ok else 1
    _, a, raw = generate()
    text = at2_text(a)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w", encoding="ascii", newline="\n") as fh:
        fh.write(text)
    print(f"wrote {args.out}")
    # the measures of the values as written (8 significant digits): what a user of the file gets
    _, written = parse_at2(text)
    report(written, raw)
    if args.plot:
        os.makedirs(os.path.dirname(os.path.abspath(args.plot)), exist_ok=True)
        plot(written, args.plot)
        print(f"wrote {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
