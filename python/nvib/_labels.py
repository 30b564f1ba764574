"""Short names for tables, legends and command-line output: each scheme's own label, and how a run ended."""

from __future__ import annotations


def scheme_label(scheme, *, iteration: bool = True) -> str:
    """LCDM, LCDM (half-step v), CEMDTS(0.45), Zhai(0.5,0.5), Newmark (newton), Newmark(1/6,0.5) (incremental),
    GαM(0.5,0.5) (newton), GαM(0,1/3,4/9,5/6) (modified), PIM, PIM(N=8, interp. 3, 2 corr.).
    ``iteration=False`` leaves the Newton mode out (a linear analysis, where it changes nothing)."""
    return scheme.label if iteration else scheme.short_label


_STATUS_TEXT = {"newton_failed": "Newton failed", "singular_matrix": "singular iteration matrix"}


def status_text(status) -> str:
    """How a run ended, in words: 'success', 'diverged', 'Newton failed', 'singular iteration matrix',
    'interrupted', 'collapsed'."""
    return _STATUS_TEXT.get(status.name, status.name)
