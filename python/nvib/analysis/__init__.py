"""Tools on top of the integrator: closed-form solutions (exact), reference
solutions (reference), accuracy against cost (cost) and stability analysis
(stability), response spectra of ground-motion records (spectrum: elastic; inelastic:
constant ductility and constant strength), incremental dynamic analysis (ida) and
fragility functions fitted to its results (fragility)."""
