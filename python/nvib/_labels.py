"""Short scheme names for tables, legends and command-line output."""

from __future__ import annotations

from fractions import Fraction

from . import _core


def _num(x: float) -> str:
    """0.25 and 0.6 as such, 1/6 rather than 0.1667."""
    if float(f"{x:.2f}") == x:
        return f"{x:g}"
    for den in range(2, 13):
        num = round(x * den)
        if abs(x * den - num) < 1e-12 and 0 < abs(num) < den:
            return str(Fraction(num, den))
    return f"{x:.4g}"


def scheme_label(scheme, *, iteration: bool = True) -> str:
    """LCDM, LCDM (half-step v), CEMDTS(0.45), Zhai(0.5,0.5), Newmark (none), Newmark(1/6,0.5) (newton),
    GαM(0.5,0.5) (newton), GαM(0,1/3,4/9,5/6) (modified), PIM, PIM(N=8, order 3, 2 corr.).
    ``iteration=False`` leaves the equilibrium iteration out (a linear analysis, where it changes nothing)."""
    g = _num
    it = f" ({scheme.iteration})" if iteration and hasattr(scheme, "iteration") else ""
    if isinstance(scheme, _core.CentralDifference):
        return "LCDM" if scheme.velocity == "synchronized" else "LCDM (half-step v)"
    if isinstance(scheme, _core.CEMDTS):
        return f"CEMDTS({g(scheme.eta)})"
    if isinstance(scheme, _core.Zhai):
        return f"Zhai({g(scheme.psi)},{g(scheme.phi)})"
    if isinstance(scheme, _core.Newmark):
        params = "" if (scheme.beta, scheme.gamma) == (0.25, 0.5) else f"({g(scheme.beta)},{g(scheme.gamma)})"
        return f"Newmark{params}{it}"
    if isinstance(scheme, _core.GeneralizedAlpha):
        params = [scheme.alpha_m, scheme.alpha_f]
        if (scheme.beta, scheme.gamma) != (0.25, 0.5):
            params += [scheme.beta, scheme.gamma]
        return f"GαM({','.join(g(p) for p in params)}){it}"
    if isinstance(scheme, _core.PreciseIntegration):
        parts = [f"N={scheme.squarings}"] if scheme.squarings != 20 else []
        if scheme.order != 2:
            parts.append(f"order {scheme.order}")
        if scheme.corrections != 1:
            parts.append(f"{scheme.corrections} corr.")
        return f"PIM({', '.join(parts)})" if parts else "PIM"
    return str(getattr(scheme, "name", scheme))
