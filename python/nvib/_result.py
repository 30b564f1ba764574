"""Result's Python members, all of them here (the C++ Result holds the history; these read what the
Python layer knows beside it). ``_core.pyi`` lists them with the C++ members; a test keeps the two equal."""

from __future__ import annotations

from ._core import Result
from ._model import unit_list
from ._solve import _extras, absolute_a, error_estimate
from ._tables import save, to_pandas, to_xarray

Result.relative_to_ground = property(
    lambda self: bool(_extras(self).get("relative_to_ground", False)),
    doc="True when the model moves on a shaking ground: u, v and a are then relative to the ground "
        "(``absolute_a`` adds the ground's acceleration back)")
Result.units = property(
    lambda self: unit_list(_extras(self).get("units", "m"), len(self.dofs)),
    doc="the unit of each saved DOF's displacement (the model's ``units``; time is in s)")
Result.warnings = property(
    lambda self: list(_extras(self).get("warnings", ())),
    doc="what a run still wants said: the model's own warnings (``Model.warnings``: a nearly singular mass, "
        "a nearly symmetric K or C), a dt above an explicit scheme's stability limit on the model's linear "
        "part, damping included (``nvib.stability.step_warning``), an energy balance error above "
        "``ENERGY_WARNING`` (5 %) of the energy scale when energy was recorded")
Result.absolute_a = property(absolute_a, doc=absolute_a.__doc__)
Result.error_estimate = property(error_estimate, doc=error_estimate.__doc__)
Result.to_pandas = to_pandas
Result.to_xarray = to_xarray
Result.save = save
